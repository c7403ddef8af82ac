"""Readers bound what they allocate by what the file holds (issue 42): a header that declares
more than the file is refused with a clear error naming the file, never a MemoryError."""

from __future__ import annotations

import struct

import numpy as np
import pytest

import dustoptics as do
from dustoptics.io import FormatError, write
from dustoptics.io.describe import describe_path


@pytest.fixture(scope="module")
def mie_cdf(tmp_path_factory):
    table = do.compute_optics(
        1.5 + 0.01j,
        do.ModifiedGamma(r_eff_um=0.5, v_eff=0.1),
        [500.0],
        np.linspace(0.0, 180.0, 19),
        rtol=1e-3,
        expansion=True,
        polarization=True,
        name="bomb",
    ).replace(cross_sections={"number_density_per_m3": 1.0e6})
    cdf = next(
        p
        for p in write(table, tmp_path_factory.mktemp("cdf"), format="libradtran-nc")
        if p.suffix == ".cdf"
    )
    return cdf.read_bytes()


def _dimension_length_offset(data: bytes) -> int:
    """Offset of the first dimension's length in a netCDF classic header (magic, numrecs,
    NC_DIMENSION tag, count, then the name's length, the padded name, its length)."""
    (name_length,) = struct.unpack(">i", data[16:20])
    return 20 + (name_length + 3) // 4 * 4


def _attribute_length_offset(data: bytes, name: bytes) -> int:
    """Offset of a global attribute's value count (after its padded name and nc_type)."""
    return data.find(name) + (len(name) + 3) // 4 * 4 + 4


@pytest.mark.parametrize("where", ["dimension", "attribute"])
def test_a_libradtran_netcdf_header_declaring_2_gib_is_a_clear_error(mie_cdf, tmp_path, where):
    data = bytearray(mie_cdf)
    offset = (
        _dimension_length_offset(data)
        if where == "dimension"
        else _attribute_length_offset(data, b"file_info")
    )
    data[offset : offset + 4] = struct.pack(">i", 0x7FFFFFFF)
    path = tmp_path / "crafted.mie.cdf"
    path.write_bytes(bytes(data))
    with pytest.raises(FormatError, match="crafted.mie.cdf"):
        describe_path(path)


def test_the_unaltered_file_is_described(mie_cdf, tmp_path):
    path = tmp_path / "whole.mie.cdf"
    path.write_bytes(mie_cdf)
    assert "libRadtran polarized optical properties" in describe_path(path)


# --- Declared sizes checked before reading (issue 42, round 4) ---------------------------------


def _classic_netcdf(path, *, n=4):
    """A small netCDF classic file (one dimension, two variables, a title) written by scipy."""
    from scipy.io import netcdf_file

    with netcdf_file(path, "w", version=2) as f:
        f.title = "a small sky"
        f.createDimension("wavelength_nm", n)
        f.createVariable("wavelength_nm", "f8", ("wavelength_nm",))[:] = np.linspace(400, 700, n)
        f.createVariable("radiance", "f8", ("wavelength_nm",))[:] = 1.0
    return path


def _patch(path, at, value):
    data = bytearray(path.read_bytes())
    data[at : at + 4] = struct.pack(">i", value)
    path.write_bytes(bytes(data))


def test_a_sky_header_declaring_2_gib_is_refused_naming_file_variable_and_size(tmp_path):
    from dustoptics.io.describe_formats import check_classic_netcdf

    path = _classic_netcdf(tmp_path / "crafted_sky.nc")
    # The dimension's length follows its padded name (4 + 16 bytes after the name's length).
    at = path.read_bytes().find(b"wavelength_nm") + 16
    _patch(path, at, 0x7FFFFFFF)
    message = r"crafted_sky\.nc.*variable 'wavelength_nm' \(shape \(2147483647,\)\) declares 17179869176 bytes"
    with pytest.raises(FormatError, match=message):
        check_classic_netcdf(path)
    with pytest.raises(FormatError, match="crafted_sky.nc"):
        describe_path(path)


def test_a_sky_attribute_declaring_2_gib_is_refused(tmp_path):
    from dustoptics.io.describe_formats import check_classic_netcdf

    path = _classic_netcdf(tmp_path / "crafted_sky.nc")
    _patch(path, path.read_bytes().find(b"title") + 12, 0x7FFFFFFF)
    with pytest.raises(FormatError, match=r"2147483648 bytes for attribute 'title'.*beyond"):
        check_classic_netcdf(path)


def test_a_whole_classic_file_passes_and_its_limit_can_be_raised_or_lowered(tmp_path):
    from dustoptics.io.describe_formats import check_classic_netcdf

    path = _classic_netcdf(tmp_path / "whole_sky.nc", n=1000)
    # 1000 float64 values in each of two variables: 8000 bytes each.
    assert check_classic_netcdf(path) == {"wavelength_nm": 8000, "radiance": 8000}
    with pytest.raises(
        FormatError, match=rf"{path.stat().st_size} bytes, larger than the 7999-byte limit"
    ):
        check_classic_netcdf(path, max_bytes=7999)
    with pytest.raises(FormatError, match=r"--max-bytes"):
        describe_path(path, max_bytes=4000)
    assert "radiance" in describe_path(path, max_bytes=10**6)


def _zarr_store(path):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("zarr")
    ds = xr.Dataset(
        {"phase": (("wavelength_nm", "theta_deg"), np.ones((3, 19)))},
        coords={"wavelength_nm": [440.0, 550.0, 680.0], "theta_deg": np.linspace(0, 180, 19)},
    )
    ds.to_zarr(path, zarr_format=2, consolidated=True)
    return path


def _edit_json(path, edit):
    import json

    data = json.loads(path.read_text())
    edit(data)
    path.write_text(json.dumps(data))


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("shape", [1 << 40], r"theta_deg.*declares 57869033041 chunks, more than the 1000000"),
        (
            "chunks",
            [1 << 31],
            r"theta_deg.*a chunk \(shape \(2147483648,\)\) declares 17179869184 bytes",
        ),
    ],
)
def test_a_zarr_array_declaring_huge_shapes_or_chunks_is_refused(tmp_path, key, value, message):
    from dustoptics.io.describe_formats import check_zarr_store

    store = _zarr_store(tmp_path / "s.zarr")
    assert check_zarr_store(store) == {"phase": 3 * 19 * 8, "wavelength_nm": 24, "theta_deg": 152}

    def edit(meta):
        meta[key] = value

    _edit_json(store / "theta_deg" / ".zarray", edit)  # the array's own file, not .zmetadata
    with pytest.raises(FormatError, match=message):
        check_zarr_store(store)


def test_zarr_metadata_that_is_not_an_arrays_is_refused(tmp_path):
    from dustoptics.io.describe_formats import check_zarr_store

    store = _zarr_store(tmp_path / "s.zarr")
    _edit_json(store / ".zmetadata", lambda m: m["metadata"]["phase/.zarray"].update(shape="x"))
    with pytest.raises(FormatError, match=r"phase.*not an array's|not Zarr array metadata"):
        check_zarr_store(store)


def test_an_hdf5_bomb_and_missing_chunks_are_refused_from_metadata(tmp_path):
    import zlib

    import h5py

    from dustoptics.io.describe_formats import check_hdf5_sizes

    path = tmp_path / "sweep.nc"
    with h5py.File(path, "w") as f:
        f.create_dataset("small", data=np.arange(10.0))
        err = f.create_dataset(
            "bomb", shape=(4, 1024, 1024), dtype="<f8", chunks=(1, 1024, 1024), compression="gzip"
        )
        block = zlib.compress(bytes(8 * 1024 * 1024), 9)
        for i in range(4):
            err.id.write_direct_chunk((i, 0, 0), block)
        f.create_dataset("hollow", shape=(1 << 20,), dtype="<f8", chunks=(1 << 16,))
    with h5py.File(path, "r+") as f:
        with pytest.raises(
            FormatError,
            match=r"'bomb' \(shape \(4, 1024, 1024\)\) declares 33554432 bytes, beyond the 1000000-byte",
        ):
            check_hdf5_sizes(path, f, max_bytes=10**6)
        with pytest.raises(FormatError, match=r"'hollow'.*declares 8388608 bytes but stores 0"):
            check_hdf5_sizes(path, f)
        del f["hollow"]
        sizes = check_hdf5_sizes(path, f, read=lambda name: name == "small", max_bytes=10**6)
    # The bomb is not read whole here (read=...): its size counts only against what is read.
    assert sizes == {"small": 80, "bomb": 33554432}


@pytest.fixture(scope="module")
def textures(tmp_path_factory):
    table = do.compute_optics(
        1.5 + 0.01j,
        do.ModifiedGamma(r_eff_um=0.5, v_eff=0.1),
        [440.0, 550.0, 680.0],
        np.linspace(0.0, 180.0, 181),
        rtol=1e-3,
        name="tex",
    )
    root = tmp_path_factory.mktemp("tex")
    (ktx2,) = write(table, root, format="ktx2")
    pytest.importorskip("OpenEXR")
    (exr,) = write(table, root, format="exr")
    return ktx2.read_bytes(), exr.read_bytes()


def test_a_ktx2_header_declaring_more_than_its_level_is_refused(textures, tmp_path):
    from dustoptics.io.textures.ktx2 import read_ktx2_metadata

    path = tmp_path / "crafted.ktx2"
    data = bytearray(textures[0])
    path.write_bytes(bytes(data))
    meta = read_ktx2_metadata(path)
    data[20:28] = struct.pack("<2I", 65535, 65535)
    path.write_bytes(bytes(data))
    with pytest.raises(FormatError, match=r"crafted\.ktx2.*for 65535 x 65535 texels"):
        read_ktx2_metadata(path)
    with pytest.raises(FormatError, match="crafted.ktx2"):
        describe_path(path)
    # A consistent header whose level lies beyond the file.
    data[20:28] = struct.pack("<2I", 1 << 20, 1 << 10)
    data[88:104] = struct.pack("<2Q", (1 << 30) * 16, (1 << 30) * 16)
    path.write_bytes(bytes(data))
    with pytest.raises(FormatError, match=r"declares 17179869184 bytes at offset \d+, beyond"):
        read_ktx2_metadata(path)
    # The metadata must say the header's size.
    data = bytearray(textures[0])
    width = meta["width"]
    data[20:24] = struct.pack("<I", width - 1)
    path.write_bytes(bytes(data))
    with pytest.raises(FormatError, match="crafted.ktx2"):
        read_ktx2_metadata(path)
    path.write_bytes(textures[0])
    with pytest.raises(FormatError, match=r"bytes, larger than the 100-byte limit"):
        read_ktx2_metadata(path, max_bytes=100)


def test_an_exr_data_window_declaring_2_30_squared_pixels_is_refused(textures, tmp_path):
    from dustoptics.io.textures.exr import read_exr_metadata

    path = tmp_path / "crafted.exr"
    data = bytearray(textures[1])
    at = data.find(b"dataWindow\0box2i\0") + len(b"dataWindow\0box2i\0") + 4
    xmax, ymax = struct.unpack("<2i", data[at + 8 : at + 16])
    path.write_bytes(bytes(data))
    assert (read_exr_metadata(path)["width"], read_exr_metadata(path)["height"]) == (
        xmax + 1,
        ymax + 1,
    )
    data[at + 8 : at + 16] = struct.pack("<2i", (1 << 30) - 1, (1 << 30) - 1)
    path.write_bytes(bytes(data))
    with pytest.raises(FormatError, match="crafted.exr"):
        read_exr_metadata(path)
    whole = tmp_path / "whole.exr"
    whole.write_bytes(textures[1])
    with pytest.raises(FormatError, match=r"whole\.exr.*larger than the 100-byte limit"):
        read_exr_metadata(whole, max_bytes=100)


def test_info_refuses_a_fifo_of_any_name_before_opening_it(tmp_path):
    import os

    for name in ("a.txt", "a_sky.nc", "a.png", "a.mie.cdf", "a.dat"):
        fifo = tmp_path / name
        os.mkfifo(fifo)
        with pytest.raises(FormatError, match=r"not a regular file"):
            describe_path(fifo)


def test_a_link_given_as_a_sweep_store_is_named_a_link(tmp_path):
    from dustoptics.sweep.store import IDENTITY, StoreLayout, held_store

    store = tmp_path / "s.zarr"
    store.mkdir()
    (store / IDENTITY).write_text("x")
    link = tmp_path / "link.zarr"
    link.symlink_to(store.name)
    layout = StoreLayout((1,), {"phase": 0}, ".")
    with (
        pytest.raises(
            ValueError,
            match=r"link\.zarr' is a symbolic link to 's\.zarr' \(a sweep store\).*out='",
        ),
        held_store(link, identity="x", layout=layout, create=lambda folder: None),
    ):
        pass
