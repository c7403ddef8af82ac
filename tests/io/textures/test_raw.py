"""Raw float32 texture with JSON sidecar: round trip, sidecar content, both samplings, damage."""

from __future__ import annotations

import hashlib
import json
import math

import numpy as np
import pytest

from dustoptics.io import FormatError
from dustoptics.io.textures.raw import (
    TEXTURE_FORMAT,
    read_texture,
    texture_values,
    write_texture,
)
from dustoptics.scattering.phase import henyey_greenstein
from dustoptics.table import Provenance, Source, Table


def make_table(n_theta: int = 181) -> Table:
    """Henyey-Greenstein phase functions (g = 0.8, 0.7, 0.6) at 440, 550, 680 nm."""
    theta = np.linspace(0.0, 180.0, n_theta)
    g = np.array([0.8, 0.7, 0.6])
    phase = np.array([henyey_greenstein(np.cos(np.deg2rad(theta)), g=x) for x in g])
    return Table(
        name="hg test/1",  # a name that is not a safe file name
        wavelength_nm=np.array([440.0, 550.0, 680.0]),
        theta_deg=theta,
        phase=phase,
        g=g,
        provenance=Provenance(
            inputs={"model": "henyey_greenstein", "g": g.tolist()},
            sources=(
                Source(name="hg", role="phase function", citation="Henyey & Greenstein 1941"),
            ),
        ),
    )


def test_theta_round_trip_and_sidecar(tmp_path) -> None:
    table = make_table()
    raw, side = write_texture(table, tmp_path, n_angles=361)
    assert (raw.name, side.name) == ("hg_test_1_phase_theta.raw", "hg_test_1_phase_theta.json")
    data = raw.read_bytes()
    assert len(data) == 3 * 361 * 4
    tex = read_texture(side)
    theta = np.linspace(0.0, 180.0, 361)
    expected = table.phase_at(theta).astype("<f4")
    np.testing.assert_array_equal(tex.phase, expected)
    assert tex.phase.dtype == np.float32 and not tex.phase.flags.writeable
    # Memory order: row = wavelength, angle fastest; little-endian float32.
    assert data[4 * 361 : 4 * 362] == np.float32(expected[1, 0]).astype("<f4").tobytes()
    np.testing.assert_array_equal(tex.theta_deg, theta)
    np.testing.assert_array_equal(tex.wavelength_nm, table.wavelength_nm)
    assert tex.mu is None and tex.sampling == "theta"
    meta = json.loads(side.read_text())
    assert meta["format"] == TEXTURE_FORMAT
    assert meta["dtype"] == "<f4" and meta["byte_order"] == "little-endian"
    assert meta["shape"] == [3, 361]
    assert meta["gl"]["width"] == 361 and meta["gl"]["height"] == 3
    assert meta["sha256"] == hashlib.sha256(data).hexdigest()
    assert meta["axes"][0]["unit"] == "nm" and meta["axes"][1]["unit"] == "deg"
    assert meta["sampling_description"].startswith(
        "uniform in theta_deg from 0 (forward, column 0) to 180"
    )
    assert meta["unit"] == "sr^-1"
    assert meta["normalization"] == "2 pi int_{-1}^{1} P(mu) dmu = 1 (per steradian)"
    assert meta["table"] == "hg test/1"
    assert meta["input_hash"] == table.provenance.input_hash
    assert meta["provenance"]["sources"][0]["citation"] == "Henyey & Greenstein 1941"
    # The HG table read linearly in angle at 1 deg integrates to 1 within 1e-3
    # (its own discretization); the texture keeps that.
    np.testing.assert_allclose(meta["sphere_integral_of_samples"], 1.0, atol=1e-3)


def test_cos_sampling_values_and_endpoints(tmp_path) -> None:
    table = make_table()
    raw, side = write_texture(table, tmp_path, sampling="cos", n_angles=2049)
    tex = read_texture(side)
    mu = np.linspace(1.0, -1.0, 2049)
    assert tex.mu[0] == 1.0 and tex.mu[-1] == -1.0 and tex.mu[1024] == 0.0
    np.testing.assert_array_equal(tex.mu, mu)
    expected = table.phase_at(np.degrees(np.arccos(mu))).astype(np.float32)
    np.testing.assert_array_equal(tex.phase, expected)
    np.testing.assert_array_equal(tex.phase[:, 0], table.phase[:, 0].astype(np.float32))
    np.testing.assert_array_equal(tex.phase[:, -1], table.phase[:, -1].astype(np.float32))
    meta = tex.metadata
    assert meta["axes"][1]["name"] == "mu"
    assert (
        "from 1 (forward, column 0) to -1 (backward, column 2048)" in meta["sampling_description"]
    )
    # Linear in mu at 2049 samples: HG g = 0.8 loses its peak's curvature; the
    # trapezoid integral (exact for that interpolation) is recorded, near 1.
    np.testing.assert_allclose(meta["sphere_integral_of_samples"], 1.0, atol=2e-3)
    assert raw.name == "hg_test_1_phase_cos.raw"


def test_deterministic_bytes(tmp_path) -> None:
    table = make_table()
    a = write_texture(table, tmp_path / "a", sampling="cos")
    b = write_texture(table, tmp_path / "b", sampling="cos")
    for x, y in zip(a, b):
        assert x.read_bytes() == y.read_bytes()


def test_no_overwrite_without_force(tmp_path) -> None:
    table = make_table()
    raw, side = write_texture(table, tmp_path)
    before = raw.read_bytes()
    with pytest.raises(FileExistsError, match="overwrite=True"):
        write_texture(table, tmp_path, n_angles=181)
    assert raw.read_bytes() == before
    write_texture(table, tmp_path, n_angles=181, overwrite=True)
    assert len(raw.read_bytes()) == 3 * 181 * 4
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [raw.name, side.name]
    )  # no temporaries


def test_truncated_raw_file_is_a_clear_error(tmp_path) -> None:
    raw, side = write_texture(make_table(), tmp_path)
    raw.write_bytes(raw.read_bytes()[:-4])
    with pytest.raises(
        FormatError, match=r"truncated: 8648 bytes, but shape \[3, 721\] of float32 needs 8652"
    ):
        read_texture(side)


def test_altered_raw_file_fails_checksum(tmp_path) -> None:
    raw, side = write_texture(make_table(), tmp_path)
    data = bytearray(raw.read_bytes())
    data[0] ^= 1
    raw.write_bytes(bytes(data))
    with pytest.raises(FormatError, match="SHA-256 .* differs from the sidecar's"):
        read_texture(side)


def test_not_a_sidecar(tmp_path) -> None:
    path = tmp_path / "x.json"
    path.write_text('{"format": "something else"}')
    with pytest.raises(
        FormatError, match="not a texture sidecar of 'dustoptics-phase-texture/1' or '.*/2'"
    ):
        read_texture(path)
    path.write_text("{")
    with pytest.raises(FormatError, match="cannot read the texture sidecar as JSON"):
        read_texture(path)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"sampling": "log"}, "sampling must be one of 'theta', 'cos'"),
        ({"n_angles": 1}, "n_angles must be an integer >= 2"),
        ({"n_angles": 100.0}, "n_angles must be an integer >= 2"),
        ({"stem": "../x"}, "stem must be a non-empty file-name stem"),
    ],
)
def test_errors(tmp_path, kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        write_texture(make_table(), tmp_path, **kwargs)


def test_texture_values_two_samples() -> None:
    # The smallest texture: the two ends, forward and backward, in both samplings.
    table = make_table()
    for sampling in ("theta", "cos"):
        phase, theta, _ = texture_values(table, sampling=sampling, n_angles=2)
        assert theta.tolist() == [0.0, 180.0]
        np.testing.assert_array_equal(phase, table.phase[:, [0, -1]].astype(np.float32))
    assert math.isclose(float(np.degrees(np.arccos(-1.0))), 180.0)


# ------------------------------------------------- the .npy sidecars, damaged sidecars (issue 29)


@pytest.mark.parametrize("layout", ["wavelength", "rgb"])
@pytest.mark.parametrize(("sampling", "precision"), [("theta", "float32"), ("cos", "float16")])
def test_reads_the_npy_textures_our_writer_writes(tmp_path, layout, sampling, precision) -> None:
    """write_npy writes format version 2; read_texture refused it before."""
    from dustoptics.io.textures.npy import write_npy
    from dustoptics.io.textures.phase_texture import phase_texture

    table = make_table()
    options = {"layout": layout, "sampling": sampling, "precision": precision, "n_angles": 91}
    array, side = write_npy(table, tmp_path, **options)
    tex = read_texture(side)
    pixels = phase_texture(table, **options).pixels
    rows = pixels[0].T if layout == "rgb" else pixels[:, :, 0]
    np.testing.assert_array_equal(tex.phase, rows.astype(np.float32))
    assert tex.phase.shape == (3, 91) and tex.sampling == sampling
    assert tex.theta_deg.size == 91 and (tex.mu is None) == (sampling == "theta")
    if layout == "wavelength":
        np.testing.assert_array_equal(tex.wavelength_nm, table.wavelength_nm)
    array.write_bytes(array.read_bytes()[:100])
    with pytest.raises(FormatError, match=r"\.npy array is truncated"):
        read_texture(side)


def _damaged_sidecars() -> list[tuple[str, object]]:
    """(path in the sidecar, replacement): entries of the wrong type or shape."""
    return [
        ("shape", [1e400]),
        ("shape", ["3", 721]),
        ("shape", [3, 721, 1]),
        ("shape", [-3, -721]),
        ("shape", None),
        ("file", 7),
        ("file", "a\x00b.raw"),
        ("file", "../x.raw"),
        ("sha256", None),
        ("axes", "values"),
        ("axes", [{"values": "abc"}, {"values": []}]),
        ("axes", [{"values": [[1.0]] * 3}, {"values": [0.0] * 721}]),
        ("axes", [{}, {}]),
        ("provenance", None),
        ("table", ["a"]),
        ("sphere_integral_of_samples", "one"),
        ("sampling", ["theta"]),
        ("dtype", {"a": 1}),
    ]


@pytest.mark.parametrize(("key", "value"), _damaged_sidecars())
def test_a_damaged_sidecar_is_a_format_error(tmp_path, key, value) -> None:
    """Valid JSON with an entry of another type: one FormatError naming the sidecar, never
    a TypeError, KeyError or OverflowError from inside the reader (nor from info)."""
    from dustoptics.io.describe import describe_path

    _, side = write_texture(make_table(), tmp_path)
    meta = json.loads(side.read_text())
    meta[key] = value
    side.write_text(json.dumps(meta))
    with pytest.raises(FormatError, match=rf"{side}|{tmp_path}"):
        read_texture(side)
    with pytest.raises(FormatError):
        describe_path(side)


def test_info_on_a_sidecar_nested_too_deeply_is_a_format_error(tmp_path) -> None:
    from dustoptics.io.describe import describe_path

    _, side = write_texture(make_table(), tmp_path)
    side.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(FormatError, match="nested deeper than 32 levels"):
        read_texture(side)
    with pytest.raises(FormatError, match="not a file dustoptics writes"):
        describe_path(side)


def test_a_texture_that_loses_its_normalization_warns_and_one_that_keeps_it_does_not(tmp_path):
    """HG g = 0.8 sampled at 31 cos(theta) steps: its first interval (0 to 21 deg) misses the
    forward peak, so the samples integrate (trapezoid rule in mu, as a renderer reads them) to
    the sum computed here independently; 361 theta steps keep it within the tolerance."""
    import warnings

    from dustoptics.io.textures.raw import NORMALIZATION_TOLERANCE, TextureNormalizationWarning

    table = make_table(n_theta=1801)
    mu = np.linspace(1.0, -1.0, 31)
    p = henyey_greenstein(mu, g=0.8)
    expected = 2 * math.pi * np.sum(0.5 * (p[1:] + p[:-1]) * -np.diff(mu))
    assert abs(expected - 1) > NORMALIZATION_TOLERANCE
    with pytest.warns(TextureNormalizationWarning, match=f"to {expected:.4g} \\(row 0\\)"):
        write_texture(table, tmp_path, sampling="cos", n_angles=31)
    with warnings.catch_warnings():
        warnings.simplefilter("error", TextureNormalizationWarning)
        write_texture(table, tmp_path / "fine", n_angles=361)


def test_an_npy_header_declaring_a_huge_array_is_refused_before_numpy_allocates(tmp_path):
    """A header rewritten to declare (100000, 100000, 3) float32 (112 GiB) in a file of a few
    hundred bytes, with the sidecar's checksum made to match: numpy allocated first."""
    import hashlib
    import re
    import struct

    from dustoptics.io.textures.npy import write_npy

    array, side = write_npy(make_table(), tmp_path, layout="rgb", n_angles=91)
    data = array.read_bytes()
    major = data[6]
    size_format, start = ("<H", 10) if major == 1 else ("<I", 12)
    (n,) = struct.unpack(size_format, data[8:start])
    header = data[start : start + n].decode("latin1")
    huge = re.sub(r"'shape': \([^)]*\)", "'shape': (100000, 100000, 3)", header).rstrip()
    crafted = data[:start] + (huge.ljust(n - 1) + "\n").encode("latin1") + data[start + n :]
    assert len(crafted) == len(data)
    array.write_bytes(crafted)
    meta = json.loads(side.read_text())
    meta["sha256"] = hashlib.sha256(crafted).hexdigest()
    side.write_text(json.dumps(meta))
    with pytest.raises(FormatError, match=r"shape \[100000, 100000, 3\]; the sidecar says"):
        read_texture(side)
