"""The sky's files written without xarray and matplotlib: the bytes those libraries write."""

from __future__ import annotations

import io
import subprocess
import sys

import numpy as np
import pytest

from dustoptics.atmosphere.sets import earth_atmosphere
from dustoptics.sky import _netcdf
from dustoptics.sky.job import sky_colour_summary
from dustoptics.sky.scene import png_bytes, sky_radiance


@pytest.fixture(scope="module")
def sky():
    atm = earth_atmosphere(wavelength_nm=list(np.linspace(360.0, 830.0, 11)))
    return sky_radiance(
        atm, sun_elevation_deg=30.0, view_zenith_deg=np.array([0.0, 45.0, 80.0, 90.0]),
        azimuth_step_deg=45.0,
    )  # fmt: skip


def test_the_sky_file_has_the_bytes_xarray_writes(sky) -> None:
    xr = pytest.importorskip("xarray")
    extra = {"inputs": '{"kind":"earth"}'}
    ds = sky.to_xarray()
    assert isinstance(ds, xr.Dataset)
    ds.attrs.update(extra)
    assert sky.netcdf_bytes(extra) == bytes(ds.to_netcdf(engine="scipy"))


def test_the_sky_file_reads_back(sky) -> None:
    variables, attrs = _netcdf.read_netcdf3(io.BytesIO(sky.netcdf_bytes({"n": 3})))
    dims, radiance = variables["radiance"]
    assert dims == ("view_zenith_angle", "view_azimuth_angle", "wavelength")
    assert radiance.tobytes() == np.ascontiguousarray(sky.radiance).tobytes()
    assert attrs["title"] == f"sky of {sky.name}"
    assert attrs["n"] == 3 and np.asarray(attrs["n"]).dtype == np.int32  # as xarray stores it


def test_the_colour_summary_reads_the_nearest_directions(sky, tmp_path) -> None:
    path = tmp_path / "sky.nc"
    path.write_bytes(sky.netcdf_bytes())
    xyz = sky.xyz()
    zenith = xyz[0, 0] / xyz[0, 0].sum()  # view zenith 0, the first azimuth
    horizon = xyz[-1, -1] / xyz[-1, -1].sum()  # view zenith 90, azimuth 180
    text = sky_colour_summary(path)
    assert text is not None
    assert f"zenith: xy {zenith[0]:.4f}, {zenith[1]:.4f}" in text
    assert f"horizon away from the Sun: xy {horizon[0]:.4f}, {horizon[1]:.4f}" in text
    assert f"luminance: {xyz[-1, -1, 1] / xyz[0, 0, 1]:.3g}" in text


def test_a_tie_goes_to_the_larger_coordinate_as_in_xarray() -> None:
    from dustoptics.sky.job import _nearest

    assert _nearest(np.array([0.0, 1.0, 2.0]), 0.5) == 1
    assert _nearest(np.array([0.0, 1.0, 2.0]), 0.4) == 0
    assert _nearest(np.array([0.0, 1.0, 2.0]), 9.0) == 2


def test_unstorable_values_are_refused() -> None:
    with pytest.raises(ValueError, match="do not fit int32"):
        _netcdf.netcdf3_bytes({}, {"x": (("x",), np.array([2**40]), {})}, {})
    with pytest.raises(ValueError, match="dimension 'x' has sizes 2 and 3"):
        _netcdf.netcdf3_bytes(
            {"a": (("x",), np.zeros(2), {})}, {"b": (("x",), np.zeros(3), {})}, {}
        )


@pytest.mark.parametrize("shape", [(1, 1, 3), (37, 91, 3), (64, 128, 3)])
def test_png_bytes_are_matplotlibs(shape) -> None:
    mpl_image = pytest.importorskip("matplotlib.image")
    rgb = np.random.default_rng(sum(shape)).integers(0, 256, shape).astype(np.uint8)
    for image in (rgb, rgb[::-1]):  # contiguous or not
        buf = io.BytesIO()
        mpl_image.imsave(buf, image, format="png", metadata={"Software": None})
        assert png_bytes(image) == buf.getvalue()


def test_the_sky_files_need_neither_xarray_nor_matplotlib() -> None:
    pytest.importorskip("matplotlib")
    code = (
        "import sys, numpy as np\n"
        "from dustoptics.sky import _netcdf, scene\n"
        "scene.check_png_support()\n"
        "scene.png_bytes(np.zeros((4, 4, 3), np.uint8))\n"
        "_netcdf.netcdf3_bytes({'a': (('x',), np.zeros(2), {'units': '1'})}, {}, {'t': 1.0})\n"
        "heavy = [m for m in ('xarray', 'matplotlib', 'dask', 'pandas') if m in sys.modules]\n"
        "assert not heavy, heavy\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
