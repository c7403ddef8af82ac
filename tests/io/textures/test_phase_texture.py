"""Texture containers (KTX2, OpenEXR, .npy): read back by independent readers and sampled
by a real OpenGL driver.

Each file is read by a reader that is not dustoptics' writer: KTX2 by
ktx-parse (npm; three.js's KTX2Loader parser; it must also serialize the
parsed file back to the same bytes), OpenEXR by the OpenEXR library, .npy by
numpy.  The pixels it returns are uploaded to Mesa's llvmpipe (moderngl, EGL;
no GPU) as RGBA32F/RGBA16F (or R32F/R16F) textures and sampled with linear
filtering at thousands of points by a compute shader: the values equal the
table's interpolation to float32 (float16) precision.
"""

from __future__ import annotations

import base64
import hashlib
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _render import EPS32, gl_context, missing

from dustoptics.io import FORMATS, write
from dustoptics.io.textures.exr import write_exr
from dustoptics.io.textures.ktx2 import KTX2_IDENTIFIER, VK_FORMATS, write_ktx2
from dustoptics.io.textures.npy import write_npy
from dustoptics.io.textures.phase_texture import phase_texture
from dustoptics.io.textures.raw import PHASE_TEXTURE_FORMAT
from dustoptics.scattering.phase import henyey_greenstein
from dustoptics.table import CrossSections, Provenance, Table

READER_DIR = Path(__file__).parents[1] / "ktx2_reader"
EPS16 = 2.0**-10  # float16 spacing at 1


def hg_table(n_theta: int = 181) -> Table:
    """Henyey-Greenstein phase functions (g = 0.8, 0.7, 0.6) at 440, 550, 680 nm, with cross-sections."""
    theta = np.linspace(0.0, 180.0, n_theta)
    mu = np.cos(np.deg2rad(theta))
    g = (0.8, 0.7, 0.6)
    return Table(
        name="hg",
        wavelength_nm=np.array([440.0, 550.0, 680.0]),
        theta_deg=theta,
        phase=np.array([henyey_greenstein(mu, g=x) for x in g]),
        g=np.array(g),
        cross_sections=CrossSections(
            cext_um2=np.array([2.0, 1.5, 1.0]), csca_um2=np.array([1.8, 1.4, 0.95])
        ),
        provenance=Provenance(inputs={"model": "hg", "g": list(g)}),
    )


TABLE = hg_table()


# ---------------------------------------------------------------- independent readers


def read_ktx2(path: Path) -> tuple[np.ndarray, dict, dict]:
    """Pixels (height, width, channels), metadata and the parsed header, through ktx-parse."""
    node = shutil.which("node")
    if node is None:
        missing("Node.js not installed (needed for the ktx-parse KTX2 reader)")
    if not (READER_DIR / "node_modules" / "ktx-parse").is_dir():
        missing(f"ktx-parse not installed: npm ci --prefix {READER_DIR}")
    result = subprocess.run(
        [node, str(READER_DIR / "read.mjs"), str(path)], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    parsed = json.loads(result.stdout)
    dtype = {4: "<f4", 2: "<f2"}[parsed["typeSize"]]
    channels = {109: 4, 97: 4, 100: 1, 76: 1}[parsed["vkFormat"]]
    data = base64.b64decode(parsed["levels"][0]["data"])
    pixels = np.frombuffer(data, dtype=dtype).reshape(
        parsed["pixelHeight"], parsed["pixelWidth"], channels
    )
    return pixels, json.loads(parsed["keyValue"]["dustoptics"]), parsed


def read_exr(path: Path) -> tuple[np.ndarray, dict]:
    OpenEXR = pytest.importorskip("OpenEXR", reason="OpenEXR not installed (the 'textures' extra)")
    with OpenEXR.File(str(path)) as image:
        meta = json.loads(image.header()["dustoptics"])
        channels = image.channels()
        # The binding groups R, G, B into one "RGB" channel of shape (height, width, 3).
        pixels = channels["RGB"].pixels if "RGB" in channels else channels["R"].pixels[:, :, None]
        pixels = np.array(pixels)
    return pixels, meta


def read_npy(path: Path) -> tuple[np.ndarray, dict]:
    meta = json.loads(path.with_suffix(".json").read_text())
    assert meta["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    return np.load(path, allow_pickle=False), meta


def read_back(container: str, path: Path) -> tuple[np.ndarray, dict]:
    if container == "ktx2":
        pixels, meta, _ = read_ktx2(path)
        return pixels, meta
    return read_exr(path) if container == "exr" else read_npy(path)


WRITERS = {"ktx2": write_ktx2, "exr": write_exr, "npy": write_npy}


# ---------------------------------------------------------------- OpenGL sampling

SAMPLE_SHADER = """
#version 430
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Coord { vec2 uv[]; };
layout(std430, binding = 1) writeonly buffer Result { vec4 value[]; };
uniform sampler2D phase;
void main() {
    uint k = gl_GlobalInvocationID.x;
    value[k] = textureLod(phase, uv[k], 0.0);
}
"""


@pytest.fixture(scope="module")
def gl():
    ctx = gl_context(require=430)
    yield ctx
    ctx.release()


def sample(ctx, pixels: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Upload ``pixels`` (height, width, channels) and sample it at ``uv`` with linear filtering."""
    import moderngl

    height, width, channels = pixels.shape
    dtype = {np.dtype("<f4"): "f4", np.dtype("<f2"): "f2"}[pixels.dtype]
    texture = ctx.texture(
        (width, height), channels, data=np.ascontiguousarray(pixels).tobytes(), dtype=dtype
    )
    texture.filter = (moderngl.LINEAR, moderngl.LINEAR)
    texture.repeat_x = texture.repeat_y = False
    n = uv.shape[0]
    groups = -(-n // 64)
    padded = np.zeros((groups * 64, 2), dtype=np.float32)
    padded[:n] = uv
    program = ctx.compute_shader(SAMPLE_SHADER)
    coords = ctx.buffer(padded.tobytes())
    out = ctx.buffer(reserve=16 * groups * 64)
    coords.bind_to_storage_buffer(0)
    out.bind_to_storage_buffer(1)
    texture.use(location=0)
    program["phase"] = 0
    program.run(group_x=groups)
    got = np.frombuffer(out.read(), dtype=np.float32).reshape(-1, 4)[:n, :channels].copy()
    for obj in (texture, program, coords, out):
        obj.release()
    return got


def columns(width: int) -> np.ndarray:
    """Continuous column positions: 4,000 across the texture, every texel centre and midpoint."""
    return np.concatenate(
        [
            np.linspace(0.0, width - 1.0, 4000),
            np.arange(width, dtype=np.float64),
            np.arange(width - 1, dtype=np.float64) + 0.5,
        ]
    )


def bilinear(values: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """GL's linear filter in float64 at texel coordinates x, y (texel centres at integers)."""
    h, w, _ = values.shape
    x = np.clip(x, 0.0, w - 1.0)
    y = np.clip(y, 0.0, h - 1.0)
    i = np.minimum(np.floor(x).astype(int), max(w - 2, 0))
    j = np.minimum(np.floor(y).astype(int), max(h - 2, 0))
    fx = (x - i)[:, None]
    fy = (y - j)[:, None]
    j1 = np.minimum(j + 1, h - 1)
    top = values[j, i] * (1 - fx) + values[j, i + 1] * fx
    bottom = values[j1, i] * (1 - fx) + values[j1, i + 1] * fx
    return top * (1 - fy) + bottom * fy


@pytest.mark.parametrize("container", ["ktx2", "exr", "npy"])
@pytest.mark.parametrize("layout", ["rgb", "wavelength"])
@pytest.mark.parametrize("precision", ["float32", "float16"])
def test_sampled_in_opengl_equals_table_interpolation(
    tmp_path, gl, container: str, layout: str, precision: str
) -> None:
    """Theta sampling on the table's own 1 deg grid: GL's linear filter is the table's
    interpolation in angle, to the samples' precision.

    Tolerance per value: the sample rounding (half an ulp of float32 or float16,
    relative), 4 float32 ulps for the filter's arithmetic, and |P[i+1] - P[i]|
    times 2^-8 for the filter weight (OpenGL and Vulkan allow 8 bits of
    sub-texel precision; llvmpipe's measured difference is printed).
    """
    (path, *_) = WRITERS[container](
        TABLE, tmp_path, layout=layout, precision=precision, n_angles=181
    )
    pixels, meta = read_back(container, path)
    assert meta["format"] == PHASE_TEXTURE_FORMAT and meta["layout"] == layout
    assert meta["sampling"] == "theta" and meta["precision"] == precision
    expected_pixels = phase_texture(TABLE, layout=layout, precision=precision, n_angles=181).pixels
    np.testing.assert_array_equal(pixels[:, :, : expected_pixels.shape[2]], expected_pixels)
    height, width, channels = pixels.shape
    x = columns(width)
    rows = range(height)
    xs = np.concatenate([x for _ in rows])
    ys = np.concatenate([np.full(x.size, float(r)) for r in rows])
    uv = np.stack([(xs + 0.5) / width, (ys + 0.5) / height], axis=1).astype(np.float32)
    got = sample(gl, pixels, uv)
    # Where the hardware samples: the float32 coordinates, in texels.
    x_hw = uv[:, 0].astype(np.float64) * width - 0.5
    y_hw = uv[:, 1].astype(np.float64) * height - 0.5
    theta = np.clip(x_hw, 0.0, width - 1.0) * 180.0 / (width - 1)
    exact_rows = TABLE.phase_at(theta)  # (3 wavelengths, n)
    if layout == "rgb":
        exact = exact_rows[[2, 1, 0]].T  # channels 680, 550, 440 nm: the table's rows
    else:
        exact = exact_rows[ys.astype(int), np.arange(xs.size)][:, None]
    stored = pixels.astype(np.float64)
    if channels == 4:  # KTX2's RGBA: A = 1
        np.testing.assert_array_equal(got[:, 3], 1.0)
    n_ch = exact.shape[1]
    near = bilinear(stored, x_hw, y_hw)[:, :n_ch]
    i = np.minimum(np.floor(np.clip(x_hw, 0, width - 1)).astype(int), width - 2)
    j = np.clip(np.round(y_hw).astype(int), 0, height - 1)
    step = np.abs(stored[j, i + 1, :n_ch] - stored[j, i, :n_ch])
    eps = EPS32 if precision == "float32" else EPS16
    tol = (0.5 * eps + 4 * EPS32) * np.abs(exact) + step * 2.0**-8
    diff = np.abs(got[:, :n_ch] - exact)
    assert np.all(diff <= tol), f"max excess {np.max(diff - tol):.3g}"
    moving = step > 0
    weight_error = np.max(np.abs(got[:, :n_ch] - near)[moving] / step[moving])
    print(
        f"{container} {layout} {precision}: max |GL - table| / |table| = "
        f"{np.max(diff / np.abs(exact)):.2e}; filter weight error {weight_error:.2e} of a step"
    )


def test_cos_sampling_is_linear_in_mu(tmp_path, gl) -> None:
    """cos(theta) sampling: the file says mu_j = 1 - 2 j / (W - 1), and GL's filter between
    columns interpolates linearly in mu the table's values at those cosines."""
    (path,) = write_ktx2(TABLE, tmp_path, sampling="cos", n_angles=1025)
    pixels, meta, _ = read_ktx2(path)
    assert "mu_j = 1 - 2 j / 1024" in meta["sampling_rule"]
    mu_nodes = np.asarray(meta["axes"]["columns"]["values"])
    np.testing.assert_array_equal(mu_nodes, np.linspace(1.0, -1.0, 1025))
    x = columns(1025)
    uv = np.stack([(x + 0.5) / 1025, np.full(x.size, 0.5)], axis=1).astype(np.float32)
    got = sample(gl, pixels, uv)[:, :3]
    x_hw = np.clip(uv[:, 0].astype(np.float64) * 1025 - 0.5, 0.0, 1024.0)
    nodes = TABLE.phase_at(np.minimum(np.degrees(np.arccos(mu_nodes)), 180.0))[[2, 1, 0]].T
    exact = np.stack([np.interp(x_hw, np.arange(1025.0), nodes[:, c]) for c in range(3)], axis=1)
    i = np.minimum(np.floor(x_hw).astype(int), 1023)
    step = np.abs(nodes[i + 1] - nodes[i])
    tol = (0.5 * EPS32 + 4 * EPS32) * np.abs(exact) + step * 2.0**-8
    assert np.all(np.abs(got - exact) <= tol)


# ---------------------------------------------------------------- container details


def test_ktx2_header_dfd_and_metadata(tmp_path) -> None:
    (path,) = write_ktx2(TABLE, tmp_path, precision="float16")
    data = path.read_bytes()
    assert data[:12] == KTX2_IDENTIFIER
    pixels, meta, parsed = read_ktx2(path)
    assert parsed["rewriteIdentical"]  # ktx-parse writes the parsed container back byte for byte
    assert parsed["vkFormat"] == VK_FORMATS[(4, "float16")] == 97  # VK_FORMAT_R16G16B16A16_SFLOAT
    assert (parsed["pixelWidth"], parsed["pixelHeight"], parsed["pixelDepth"]) == (721, 1, 0)
    assert parsed["levelCount"] == 1 and parsed["supercompressionScheme"] == 0
    dfd = parsed["dataFormatDescriptor"][0]
    assert dfd["colorModel"] == 1 and dfd["transferFunction"] == 1  # RGBSDA, linear
    assert [s["channelType"] & 0x0F for s in dfd["samples"]] == [0, 1, 2, 15]  # R, G, B, A
    assert all(s["channelType"] & 0xC0 == 0xC0 for s in dfd["samples"])  # float, signed
    assert [s["bitOffset"] for s in dfd["samples"]] == [0, 16, 32, 48]
    assert parsed["keyValue"]["KTXwriter"].startswith("dustoptics ")
    assert meta["input_hash"] == TABLE.provenance.input_hash
    assert meta["unit"] == "sr^-1" and meta["max_relative_rounding_error"] <= 2.0**-11
    np.testing.assert_array_equal(pixels[0, :, 3], np.float16(1.0))


def test_same_bytes_and_no_overwrite(tmp_path) -> None:
    for container, writer in WRITERS.items():
        first = writer(TABLE, tmp_path / "a", layout="wavelength", sampling="cos")
        second = writer(TABLE, tmp_path / "b", layout="wavelength", sampling="cos")
        for p, q in zip(first, second):
            assert p.read_bytes() == q.read_bytes(), container
        with pytest.raises(FileExistsError, match="overwrite=True"):
            writer(TABLE, tmp_path / "a", layout="wavelength", sampling="cos")


def test_file_names_and_targets(tmp_path) -> None:
    """One naming rule for every container; a path with the container's suffix is the file
    itself (KTX2, OpenEXR), while the .npy writer always takes a directory (two files)."""
    stem = "mars_dust_1_phase_wavelength_cos_float16"
    table = TABLE.replace(name="mars dust/1")
    options = {"layout": "wavelength", "sampling": "cos", "precision": "float16"}
    for container, writer in WRITERS.items():
        paths = writer(table, tmp_path / container, **options)
        assert paths[0] == tmp_path / container / f"{stem}.{container}"
    assert write_ktx2(TABLE, tmp_path / "t.ktx2") == [tmp_path / "t.ktx2"]
    assert write_exr(TABLE, tmp_path / "t.exr") == [tmp_path / "t.exr"]
    root = tmp_path / "t.npy"
    assert write_npy(TABLE, root) == [
        root / "hg_phase_rgb_theta_float32.npy",
        root / "hg_phase_rgb_theta_float32.json",
    ]


def test_registry_and_npy_sidecar(tmp_path) -> None:
    assert {"ktx2", "exr", "npy"} <= set(FORMATS)
    paths = write(
        TABLE, tmp_path, format="npy", layout="rgb", colour="cie1931-xyz", min_band_coverage=0.0
    )
    assert [p.suffix for p in paths] == [".npy", ".json"]
    pixels, meta = read_npy(paths[0])
    assert pixels.shape == (1, 721, 3) and pixels.dtype == np.float32
    assert meta["channels"]["mode"] == "cie1931-xyz" and meta["channel_names"] == ["R", "G", "B"]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"layout": "hemisphere"}, "layout must be one of 'wavelength', 'rgb'"),
        ({"precision": "float64"}, "precision must be one of 'float32', 'float16'"),
        ({"sampling": "log"}, "sampling must be one of 'theta', 'cos'"),
        ({"n_angles": 5000}, r"width \(angle samples\) = 5000 exceeds max_dimension = 4096"),
        ({"n_angles": 1}, "n_angles must be an integer from 2"),
        (
            {"layout": "wavelength", "colour": "cie1931-xyz"},
            "with layout='wavelength' every wavelength is a row",
        ),
        ({"channels_nm": (900.0, 550.0, 440.0)}, r"900 nm is outside"),
    ],
)
def test_bad_input_is_refused_before_writing(tmp_path, kwargs: dict, message: str) -> None:
    for writer in WRITERS.values():
        with pytest.raises(ValueError, match=message):
            writer(TABLE, tmp_path / "out", **kwargs)
    assert not (tmp_path / "out").exists()


def test_float16_overflow_is_an_error(tmp_path) -> None:
    table = TABLE.replace(phase=TABLE.phase * 1e5)  # beyond float16's 65504
    with pytest.raises(ValueError, match="precision='float16' cannot hold"):
        write_ktx2(table, tmp_path, precision="float16")
    assert list(tmp_path.iterdir()) == []


def test_unknown_container_is_a_clear_error(tmp_path) -> None:
    with pytest.raises(ValueError, match="format must be one of .*'ktx2'.*; got 'dds'"):
        write(TABLE, tmp_path, format="dds")


def test_cli_writes_every_container(tmp_path) -> None:
    from dustoptics.cli import main
    from dustoptics.io import write_hdf5

    h5 = write_hdf5(TABLE, tmp_path / "hg.h5")
    out = tmp_path / "out"
    argv = [
        "export",
        str(h5),
        "--out",
        str(out),
        "--format",
        "ktx2,exr,npy",
        "--layout",
        "wavelength",
        "--sampling",
        "cos",
        "--n-angles",
        "1025",
        "--precision",
        "float16",
        "--quiet",
    ]
    assert main(argv) == 0
    names = sorted(p.name for p in (out / "hg").iterdir())
    stem = "hg_phase_wavelength_cos_float16"
    assert names == [f"{stem}.exr", f"{stem}.json", f"{stem}.ktx2", f"{stem}.npy"]
    too_wide = [
        "export",
        str(h5),
        "--out",
        str(out),
        "--format",
        "ktx2",
        "--n-angles",
        "9000",
        "--force",
    ]
    assert main(too_wide) == 1  # refused before writing: the files already there are untouched
    assert sorted(p.name for p in (out / "hg").iterdir()) == names


def test_exr_without_openexr_names_the_extra(tmp_path, monkeypatch) -> None:
    import builtins

    real_import = builtins.__import__

    def no_openexr(name, *args, **kwargs):
        if name == "OpenEXR":
            raise ImportError("No module named 'OpenEXR'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_openexr)
    with pytest.raises(
        ImportError, match=r"a dependency of dustoptics: pip install 'OpenEXR>=3\.3'"
    ):
        write_exr(TABLE, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_container_limits_are_checked() -> None:
    from dustoptics.io.textures.phase_texture import check_dimensions

    # KTX2 stores the width as uint32, OpenEXR its data window as int32.
    with pytest.raises(ValueError, match="exceeds the KTX2 container's limit of 4294967295 texels"):
        check_dimensions(2**32, 1, max_dimension=2**40, container="KTX2", container_limit=2**32 - 1)
    with pytest.raises(ValueError, match=r"height \(rows\) = 2147483648 exceeds the OpenEXR"):
        check_dimensions(
            2, 2**31, max_dimension=2**40, container="OpenEXR", container_limit=2**31 - 1
        )
