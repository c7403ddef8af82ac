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
