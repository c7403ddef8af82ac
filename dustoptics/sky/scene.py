"""A sky as data and as pictures: radiance over the sky dome, colour, images.

:func:`sky_radiance` computes the spectral radiance of the whole sky seen by
an observer near the ground, on a grid of viewing zenith angles and azimuths
from the Sun (the sky is symmetric about the solar vertical plane, so
azimuths 0 to 180 deg suffice).  :class:`SkyRadiance` holds it with its
accuracy and converts it to CIE XYZ (tabulated CIE 1931 colour-matching
functions, sunlight of the ASTM G-173 spectrum) and to display sRGB images:
a fisheye (equidistant, zenith at the centre) and a panorama
(equirectangular).  Exposure is explicit: display white is
``Y * exposure = 1``, with Y the luminance factor (radiance times the solar
spectrum, per unit of the Sun's illuminance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from dustoptics import colour
from dustoptics._validation import check_closed_interval, check_positive
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.sky.medium import Medium
from dustoptics.sky.orders import DiffuseField, solve_orders
from dustoptics.sky.render import line_of_sight_radiance

__all__ = [
    "ILLUMINANT",
    "SkyRadiance",
    "default_view_zenith_deg",
    "display_rgb",
    "png_bytes",
    "sky_radiance",
    "sunlit_xyz",
]

#: Spectrum of the sunlight that lights every sky (shape only; see colour).
ILLUMINANT: Final = "astm-g173"


def default_view_zenith_deg() -> np.ndarray:
    """Viewing zenith angles: 1 deg steps, 0.25 deg over the last 10 deg to the horizon. [deg]"""
    return np.unique(np.concatenate([np.arange(0.0, 80.0, 1.0), np.arange(80.0, 90.01, 0.25)]))


@dataclass(frozen=True, eq=False)
class SkyRadiance:
    """Spectral radiance of the sky over the upper hemisphere.

    Attributes
    ----------
    name : str
        The atmosphere's name.
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        Wavelengths. [nm]
    view_zenith_deg : numpy.ndarray, shape (n_zenith,)
        Viewing zenith angles, 0 (zenith) to 90 (horizon). [deg]
    view_azimuth_deg : numpy.ndarray, shape (n_azimuth,)
        Viewing azimuths from the Sun's, 0 (toward the Sun) to 180. [deg]
    radiance : numpy.ndarray, shape (n_zenith, n_azimuth, n_wavelength)
        Radiance per unit solar irradiance normal to the beam (direct Sun
        excluded). [sr^-1]
    sun_zenith_deg : float
        The Sun's zenith angle at the observer. [deg]
    observer_altitude_m : float
        Observer above the ground. [m]
    ground_albedo : numpy.ndarray, shape (n_wavelength,)
        Lambertian ground albedo. [-]
    sun_transmittance : numpy.ndarray, shape (n_wavelength,)
        Transmittance of the direct Sun to the observer (true extinction,
        spherical path; 0 below the horizon). [-]
    n_orders : int
        Orders of scattering summed.
    error_estimate : float
        Estimated relative remainder of the series of orders. [-]
    tol : float
        Requested tolerance of the series. [-]
    """

    name: str
    wavelength_nm: np.ndarray
    view_zenith_deg: np.ndarray
    view_azimuth_deg: np.ndarray
    radiance: np.ndarray
    sun_zenith_deg: float
    observer_altitude_m: float
    ground_albedo: np.ndarray
    sun_transmittance: np.ndarray
    n_orders: int
    error_estimate: float
    tol: float

    @property
    def sun_elevation_deg(self) -> float:
        """The Sun's elevation, 90 - zenith angle. [deg]"""
        return 90.0 - self.sun_zenith_deg

    def at(self, view_zenith_deg: Any, view_azimuth_deg: Any) -> np.ndarray:
        """Radiance in other directions (bilinear in zenith and azimuth). [sr^-1]

        Azimuths are folded into [0, 180] by the sky's mirror symmetry.
        Returns shape ``broadcast(zenith, azimuth).shape + (n_wavelength,)``.
        """
        z, a = np.broadcast_arrays(
            np.asarray(view_zenith_deg, dtype=float), np.asarray(view_azimuth_deg, dtype=float)
        )
        a = np.abs((a + 180.0) % 360.0 - 180.0)
        zg, ag = self.view_zenith_deg, self.view_azimuth_deg
        if np.any((z < zg[0]) | (z > zg[-1])):
            raise ValueError(
                f"view_zenith_deg must be within [{zg[0]:g}, {zg[-1]:g}] deg (the computed sky)"
            )
        iz = np.clip(np.searchsorted(zg, z) - 1, 0, zg.size - 2)
        fz = ((z - zg[iz]) / (zg[iz + 1] - zg[iz]))[..., None]
        ia = np.clip(np.searchsorted(ag, a) - 1, 0, ag.size - 2)
        fa = ((a - ag[ia]) / (ag[ia + 1] - ag[ia]))[..., None]
        r = self.radiance
        return (
            r[iz, ia] * (1 - fz) * (1 - fa)
            + r[iz + 1, ia] * fz * (1 - fa)
            + r[iz, ia + 1] * (1 - fz) * fa
            + r[iz + 1, ia + 1] * fz * fa
        )

    def xyz(self, radiance: np.ndarray | None = None) -> np.ndarray:
        """CIE 1931 XYZ of radiances under sunlight, per unit solar illuminance.

        ``Y`` is the luminance factor: radiance weighted by the Sun's spectrum
        and ybar, divided by the Sun's own ``int S ybar``. [sr^-1]
        """
        spectra = self.radiance if radiance is None else radiance
        return sunlit_xyz(self.wavelength_nm, spectra)

    def chromaticity(self, radiance: np.ndarray | None = None) -> np.ndarray:
        """CIE 1931 (x, y) chromaticity of radiances under sunlight. [-]"""
        xyz = self.xyz(radiance)
        return xyz[..., :2] / xyz.sum(axis=-1, keepdims=True)

    def default_exposure(self) -> float:
        """Exposure that puts the 99th percentile of the sky's luminance at white.

        Only the brightest 1 % of the computed directions (the Sun's aureole)
        clip, so the aureole's colour stays visible.
        """
        y = self.xyz()[..., 1]
        return float(1.0 / np.percentile(y, 99.0))

    def fisheye(self, *, size: int = 512, exposure: float | None = None) -> np.ndarray:
        """Display sRGB fisheye image (equidistant; zenith centre, horizon rim).

        The Sun's azimuth points up in the image.  Pixels outside the horizon
        circle are black.

        Returns
        -------
        numpy.ndarray, shape (size, size, 3), dtype uint8
        """
        if not (isinstance(size, int) and 16 <= size <= 8192):
            raise ValueError(f"size must be an integer in [16, 8192] pixels; got {size!r}")
        e = self.default_exposure() if exposure is None else check_positive("exposure", exposure)
        c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
        xx, yy = np.meshgrid(c, -c)
        rad = np.hypot(xx, yy)
        inside = rad <= 1.0
        zen = np.where(inside, rad * 90.0, 0.0)
        azi = np.rad2deg(np.arctan2(xx, yy))
        rgb = self._display(self.at(zen, azi), e)
        rgb[~inside] = 0
        return rgb

    def panorama(
        self, *, width: int = 1024, height: int = 256, exposure: float | None = None
    ) -> np.ndarray:
        """Display sRGB panorama: azimuth -180..180 (Sun at the centre), elevation 0..90.

        Returns
        -------
        numpy.ndarray, shape (height, width, 3), dtype uint8
        """
        for key, value in (("width", width), ("height", height)):
            if not (isinstance(value, int) and 8 <= value <= 16384):
                raise ValueError(f"{key} must be an integer in [8, 16384] pixels; got {value!r}")
        e = self.default_exposure() if exposure is None else check_positive("exposure", exposure)
        azi = (np.arange(width) + 0.5) / width * 360.0 - 180.0
        elev = 90.0 - (np.arange(height) + 0.5) / height * 90.0
        aa, ee = np.meshgrid(azi, elev)
        return self._display(self.at(90.0 - ee, aa), e)

    def to_xarray(self) -> Any:
        """The sky as an ``xarray.Dataset`` (radiance, XYZ, chromaticity)."""
        import xarray as xr

        xyz = self.xyz()
        dims = ("view_zenith_angle", "view_azimuth_angle")
        return xr.Dataset(
            {
                "radiance": (
                    dims + ("wavelength",),
                    self.radiance,
                    {
                        "units": "sr-1",
                        "long_name": "sky radiance per unit solar irradiance normal to the beam",
                    },
                ),
                "luminance_factor": (
                    dims,
                    xyz[..., 1],
                    {"units": "sr-1", "long_name": "CIE Y under ASTM G-173 sunlight per solar Y"},
                ),
                "chromaticity_x": (dims, xyz[..., 0] / xyz.sum(-1), {"units": "1"}),
                "chromaticity_y": (dims, xyz[..., 1] / xyz.sum(-1), {"units": "1"}),
                "sun_transmittance": (
                    ("wavelength",),
                    self.sun_transmittance,
                    {"units": "1", "long_name": "direct transmittance of the Sun to the observer"},
                ),
                "ground_albedo": (("wavelength",), self.ground_albedo, {"units": "1"}),
            },
            coords={
                "view_zenith_angle": (
                    "view_zenith_angle",
                    self.view_zenith_deg,
                    {"units": "degree"},
                ),
                "view_azimuth_angle": (
                    "view_azimuth_angle",
                    self.view_azimuth_deg,
                    {"units": "degree", "long_name": "azimuth from the Sun's"},
                ),
                "wavelength": ("wavelength", self.wavelength_nm, {"units": "nm"}),
            },
            attrs={
                "title": f"sky of {self.name}",
                "sun_zenith_angle_degree": self.sun_zenith_deg,
                "observer_altitude_m": self.observer_altitude_m,
                "orders_of_scattering": self.n_orders,
                "orders_error_estimate": self.error_estimate,
                "orders_tolerance": self.tol,
                "illuminant": "ASTM G-173 extraterrestrial (shape), CIE 1931 2-degree observer",
            },
        )

    def _display(self, spectra: np.ndarray, exposure: float) -> np.ndarray:
        return display_rgb(self.xyz(spectra), exposure)


def sunlit_xyz(wavelength_nm: np.ndarray, spectra: np.ndarray) -> np.ndarray:
    """CIE 1931 XYZ of radiances under sunlight, per unit solar illuminance. [sr^-1]

    ``spectra`` has the wavelengths last; ``Y`` is the luminance factor.
    """
    sun = colour.spectrum_to_xyz(wavelength_nm, np.ones(wavelength_nm.size), illuminant=ILLUMINANT)
    return colour.spectrum_to_xyz(wavelength_nm, spectra, illuminant=ILLUMINANT) / sun[1]


def display_rgb(xyz: np.ndarray, exposure: float) -> np.ndarray:
    """8-bit display sRGB of XYZ with white at ``Y * exposure = 1``."""
    rgb = colour.xyz_to_display(xyz, exposure=exposure)
    return np.round(rgb * 255.0).astype(np.uint8)


def sky_radiance(
    atmosphere: Atmosphere | Medium,
    *,
    sun_elevation_deg: float,
    ground_albedo: float | np.ndarray = 0.2,
    observer_altitude_m: float = 2.0,
    tol: float = 1e-4,
    view_zenith_deg: np.ndarray | None = None,
    azimuth_step_deg: float = 2.0,
    field: DiffuseField | None = None,
) -> SkyRadiance:
    """The spectral sky over an observer near the ground.

    Parameters
    ----------
    atmosphere : Atmosphere or Medium
        An atmosphere set (:mod:`dustoptics.atmosphere.sets`) or its medium
        (to reuse the precomputed optics for many Sun positions).
    sun_elevation_deg : float
        Sun above the horizon, -10 .. 90 (a Sun a little below the horizon
        still lights the upper atmosphere). [deg]
    ground_albedo : float or array_like
        Lambertian ground albedo, one value or one per wavelength. [-]
    observer_altitude_m : float
        Observer above the ground (a rover's camera: 2 m). [m]
    tol : float
        Tolerance of the series of orders of scattering. [-]
    view_zenith_deg : array_like, optional
        Viewing zenith angles (default :func:`default_view_zenith_deg`). [deg]
    azimuth_step_deg : float
        Step of the viewing azimuths from 0 to 180 deg. [deg]
    field : DiffuseField, optional
        The diffuse field already solved for this medium and Sun
        (:func:`~dustoptics.sky.orders.solve_orders` with ``tol``), to render
        the dome without solving again; ``ground_albedo`` must equal the
        field's.

    Returns
    -------
    SkyRadiance
    """
    medium = atmosphere if isinstance(atmosphere, Medium) else Medium.from_atmosphere(atmosphere)
    elev = check_closed_interval("sun_elevation_deg", sun_elevation_deg, -10.0, 90.0)
    step = check_closed_interval("azimuth_step_deg", azimuth_step_deg, 0.05, 45.0)
    zen = (
        default_view_zenith_deg() if view_zenith_deg is None else np.asarray(view_zenith_deg, float)
    )
    if zen.ndim != 1 or zen.size < 2 or np.any(np.diff(zen) <= 0) or zen[0] < 0 or zen[-1] > 90:
        raise ValueError("view_zenith_deg must increase strictly within [0, 90] deg")
    n_az = round(180.0 / step) + 1
    azi = np.linspace(0.0, 180.0, n_az)
    if field is None:
        field = solve_orders(
            medium, sun_zenith_deg=90.0 - elev, ground_albedo=ground_albedo, tol=tol
        )
    elif not isinstance(field, DiffuseField):
        raise TypeError(f"field must be a DiffuseField; got {type(field).__name__}")
    elif abs(field.mu0 - math.cos(math.radians(90.0 - elev))) > 1e-12:
        raise ValueError(
            f"field was solved for a Sun at {90.0 - math.degrees(math.acos(field.mu0)):g} deg "
            f"elevation; sun_elevation_deg is {elev!r}"
        )
    elif field.ground_albedo.size != medium.wavelength_nm.size or not np.allclose(
        np.broadcast_to(np.asarray(ground_albedo, dtype=float), field.ground_albedo.shape),
        field.ground_albedo,
    ):
        raise ValueError(
            f"ground_albedo {ground_albedo!r} differs from the field's "
            f"({field.ground_albedo.tolist()!r})"
        )
    zz, aa = np.meshgrid(zen, azi, indexing="ij")
    radiance = line_of_sight_radiance(
        medium,
        field,
        view_zenith_deg=zz,
        view_azimuth_deg=aa,
        observer_altitude_m=observer_altitude_m,
    )
    t_sun = medium.transmittance(
        np.array(medium.planet_radius_m + observer_altitude_m),
        np.array(math.cos(math.radians(90.0 - elev))),
    )
    return SkyRadiance(
        name=medium.name,
        wavelength_nm=medium.wavelength_nm,
        view_zenith_deg=zen,
        view_azimuth_deg=azi,
        radiance=radiance,
        sun_zenith_deg=90.0 - elev,
        observer_altitude_m=float(observer_altitude_m),
        ground_albedo=field.ground_albedo,
        sun_transmittance=np.asarray(t_sun, dtype=float).reshape(-1),
        n_orders=field.n_orders,
        error_estimate=float(np.max(field.error_estimate)),
        tol=float(tol),
    )


def png_bytes(rgb: np.ndarray) -> bytes:
    """PNG file contents of an 8-bit RGB image, without time stamps (same bytes each time).

    Needs the ``plot`` extra (matplotlib).
    """
    import io as _io

    try:
        import matplotlib.image
    except ImportError as exc:  # pragma: no cover - depends on the extra
        raise ImportError(
            "writing PNG images needs matplotlib: pip install 'dustoptics[plot]'"
        ) from exc
    buf = _io.BytesIO()
    no_stamp: dict[str, Any] = {"Software": None}  # same bytes on every run
    matplotlib.image.imsave(buf, rgb, format="png", metadata=no_stamp)
    return buf.getvalue()
