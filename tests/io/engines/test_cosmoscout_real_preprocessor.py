"""CosmoScout VR's own ``bruneton-preprocessor`` on the sets dustoptics writes.

Runs only where ``COSMOSCOUT_VR_DIR`` names a work tree of cosmoscout/cosmoscout-vr (at least
``plugins/csp-atmospheres``) and the build tools of ``scripts/cosmoscout_preprocessor.py`` are
installed (g++, SDL2, GLEW, GLM, libtiff, nlohmann-json, Boost.Filesystem, xvfb-run): the
script compiles the preprocessor's sources unchanged with the stand-in of
``scripts/cosmoscout_shim`` and runs it headless on Mesa (seconds per set: every option the
transmittance reads as the set writes it, no multiple scattering, small scattering textures).

The numbers checked: the transmittance CosmoScout's code computes against ``exp(-tau)``, tau
computed independently here from the CSV files (and from the set's profiles), within the 0.5 %
the settings are chosen for; the same code with its own defaults is outside it (so the check
can fail); and dustoptics' simulation of its quadrature
(:func:`~dustoptics.io.engines.cosmoscout_preprocessor.preprocessor_transmittance`, which
chooses the settings) agrees with the real output.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import sys
from pathlib import Path

import numpy as np
import pytest

_SPEC = importlib.util.spec_from_file_location(
    "dustoptics_cosmoscout_preprocessor",
    Path(__file__).resolve().parents[3] / "scripts" / "cosmoscout_preprocessor.py",
)
assert _SPEC is not None and _SPEC.loader is not None
script = importlib.util.module_from_spec(_SPEC)
sys.modules[_SPEC.name] = script  # dataclasses look their module up while being defined
_SPEC.loader.exec_module(script)


def _checkout() -> Path | None:
    try:
        return script.cosmoscout_dir()
    except script.SetupError:
        return None


CHECKOUT = _checkout()
needs_checkout = pytest.mark.skipif(
    CHECKOUT is None,
    reason="COSMOSCOUT_VR_DIR does not name a work tree of cosmoscout/cosmoscout-vr",
)
MISSING = ["a checkout in COSMOSCOUT_VR_DIR"] if CHECKOUT is None else script.missing_tools()
needs_tools = pytest.mark.skipif(bool(MISSING), reason=f"needs {MISSING}")


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("cosmoscout")


@pytest.fixture(scope="module")
def binary(work: Path) -> Path:
    assert CHECKOUT is not None
    return script.build_preprocessor(CHECKOUT, work / "build")


@pytest.fixture(scope="module")
def runs(work: Path, binary: Path) -> dict:
    assert CHECKOUT is not None
    return {
        (name, mode): script.run(name, root=CHECKOUT, work=work, mode=mode, binary=binary)
        for name in ("mars", "earth")
        for mode in ("transmittance", "defaults")
    }


@needs_checkout
def test_every_option_written_is_one_the_preprocessor_reads(tmp_path: Path) -> None:
    # The keys its Params.cpp deserialises, read from CosmoScout's source.
    assert CHECKOUT is not None
    params = (CHECKOUT / script.PREPROCESSOR / "Params.cpp").read_text()
    body = params.split("from_json(nlohmann::json const& j, Params& o) {")[1].split("\n}")[0]
    top = set(re.findall(r'deserialize\(\s*j,\s*"(\w+)",\s*o\.m', body))
    assert {"stepSizeOpticalDepth", "multiScatteringOrder", "refraction"} <= top
    _, settings_path = script.write_set("mars", tmp_path)
    settings = json.loads(settings_path.read_text())
    written = set(settings) - {"dustoptics"}  # its own record, which the preprocessor ignores
    assert written <= top, written - top
    # Every option it reads is stated (ozone only where the set has it).
    assert top - written == {"ozone"}
    for component in ("molecules", "aerosols"):
        assert all(
            Path(p).is_absolute() and Path(p).is_file() for p in settings[component].values()
        )


@needs_tools
@pytest.mark.parametrize("name", ["mars", "earth"])
def test_zenith_transmittance_within_half_a_percent_of_exp_minus_tau(runs: dict, name: str) -> None:
    result = runs[(name, "transmittance")]
    mu, got, csv, profile = result.rows[0]
    assert mu == 1.0
    assert result.wavelength_nm == (680.0, 550.0, 440.0)
    np.testing.assert_allclose(got, csv, rtol=0.005, atol=0)
    np.testing.assert_allclose(got, profile, rtol=0.005, atol=0)
    assert result.zenith_error <= 0.005


@needs_tools
def test_mars_slant_rays_within_half_a_percent(runs: dict) -> None:
    # Refraction is off for Mars: the preprocessor's rays are the straight rays integrated here.
    result = runs[("mars", "transmittance")]
    assert not result.refraction
    for mu, got, csv, _ in result.rows[1:]:
        assert mu < 0.6
        np.testing.assert_allclose(got, csv, rtol=0.005, atol=0)


@needs_tools
@pytest.mark.parametrize("name", ["mars", "earth"])
def test_the_preprocessor_defaults_are_outside(runs: dict, name: str) -> None:
    # Its own defaults (10 km steps, refraction on) on the same files: the error the settings fix.
    assert runs[(name, "defaults")].zenith_error > 0.02


@needs_tools
@pytest.mark.parametrize("mode", ["transmittance", "defaults"])
@pytest.mark.parametrize("name", ["mars", "earth"])
def test_dustoptics_simulates_the_real_quadrature(runs: dict, name: str, mode: str) -> None:
    # The Python quadrature that chooses the settings, against the GPU's float32 result.
    assert runs[(name, mode)].simulation_error < 1e-4


def test_tiff_reader_round_trip(tmp_path: Path) -> None:
    # The reader against a TIFF written here by the rules the preprocessor's writer follows
    # (little-endian, 32-bit float RGB, one row per strip), two pages.
    import struct

    pages = np.arange(2 * 3 * 4 * 3, dtype="<f4").reshape(2, 3, 4, 3) / 7.0
    height, width = 3, 4
    out = bytearray(b"II" + struct.pack("<HI", 42, 0))
    previous = 4
    for page in pages:
        strips = []
        for row in page:
            strips.append((len(out), row.nbytes))
            out += row.tobytes()
        offsets_at = len(out)
        out += struct.pack("<" + "I" * height, *(o for o, _ in strips))
        counts_at = len(out)
        out += struct.pack("<" + "I" * height, *(c for _, c in strips))
        bits_at = len(out)
        out += struct.pack("<HHH", 32, 32, 32)
        ifd = len(out)
        struct.pack_into("<I", out, previous, ifd)
        entries = [
            (256, 4, 1, width), (257, 4, 1, height), (258, 3, 3, bits_at), (259, 3, 1, 1),
            (262, 3, 1, 2), (273, 4, height, offsets_at), (277, 3, 1, 3), (278, 4, 1, 1),
            (279, 4, height, counts_at), (284, 3, 1, 1), (339, 3, 1, 3),
        ]  # fmt: skip
        out += struct.pack("<H", len(entries))
        for tag, kind, count, value in entries:
            packed = struct.pack("<HHI", tag, kind, count)
            packed += (
                struct.pack("<HH", value, 0)
                if kind == 3 and count == 1
                else struct.pack("<I", value)
            )
            out += packed
        previous = len(out)
        out += struct.pack("<I", 0)
    path = tmp_path / "two.tif"
    path.write_bytes(bytes(out))
    np.testing.assert_array_equal(script.read_tiff(path), pages)


def test_settings_for_a_run_keep_what_the_transmittance_reads(tmp_path: Path) -> None:
    source = {
        "minAltitude": 1.0, "maxAltitude": 2.0, "refraction": False,
        "stepSizeOpticalDepth": 300, "sampleCountOpticalDepth": 700,
        "multiScatteringOrder": 12, "scatteringTextureNuSize": 64,
    }  # fmt: skip
    path = tmp_path / "s.json"
    path.write_text(json.dumps(source))
    fast = json.loads(
        script.run_settings(path, tmp_path / "f.json", mode="transmittance").read_text()
    )
    for key in ("refraction", "stepSizeOpticalDepth", "sampleCountOpticalDepth"):
        assert fast[key] == source[key]
    assert fast["multiScatteringOrder"] == 0
    defaults = json.loads(
        script.run_settings(path, tmp_path / "d.json", mode="defaults").read_text()
    )
    assert "stepSizeOpticalDepth" not in defaults and "refraction" not in defaults
    assert script.run_settings(path, tmp_path / "x.json", mode="full") == path
    with pytest.raises(ValueError, match="mode must be"):
        script.run_settings(path, tmp_path / "x.json", mode="fast")


def test_missing_checkout_is_named(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("COSMOSCOUT_VR_DIR", raising=False)
    with pytest.raises(script.SetupError, match="COSMOSCOUT_VR_DIR is not set"):
        script.cosmoscout_dir()
    with pytest.raises(script.SetupError, match="lacks"):
        script.cosmoscout_dir(os.fspath(tmp_path))
    assert script.main(["--cosmoscout", os.fspath(tmp_path)]) == 2
