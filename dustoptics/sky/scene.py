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

The sky's accuracy travels with it: the series' tolerance and remainder, and
the estimated relative error of the radiance per wavelength
(:func:`~dustoptics.sky.accuracy.radiance_error_estimate`, a model checked
against CDISORT).  Every computation is held to an up-front estimate of its
memory and work (``allow_large=True`` lifts it) and reports its progress on a
text stream when it takes longer than two seconds (``progress=``).
"""

from __future__ import annotations

import importlib.util
import io as _io
import math
from collections.abc import Mapping
from dataclasses import dataclass
from dataclasses import field as dataclass_field
from typing import Any, Final, TextIO

import numpy as np

from dustoptics import colour
from dustoptics._validation import (
    MEMORY_BUDGET_BYTES,
    BudgetError,
    check_closed_interval,
    check_positive,
)
from dustoptics.atmosphere.sets import Atmosphere
from dustoptics.sky._netcdf import Variable, netcdf3_bytes
from dustoptics.sky._progress import Reporter, reporter
from dustoptics.sky.accuracy import VALIDATED_DOMAIN, radiance_error_estimate
from dustoptics.sky.medium import Medium
from dustoptics.sky.orders import N_LAYERS, DiffuseField, check_orders_cost, solve_orders
from dustoptics.sky.render import N_PATH, check_render_cost, line_of_sight_radiance

__all__ = [
    "EXPOSURE_SUN_EXCLUSION_DEG",
    "ILLUMINANT",
    "MAX_IMAGE_SIZE",
    "SUN_RADIUS_M",
    "SkyRadiance",
    "check_image_size",
    "check_png_support",
    "default_view_zenith_deg",
    "display_rgb",
    "png_bytes",
    "sky_radiance",
    "sun_angular_radius_deg_of",
    "sun_disc_xyz",
    "sunlit_xyz",
]

#: Spectrum of the sunlight that lights every sky (shape only; see colour).
ILLUMINANT: Final = "astm-g173"
#: Largest image side without ``allow_large`` (a 8192 x 8192 fisheye: 0.2 GB
#: of pixels, a few seconds). [pixels]
MAX_IMAGE_SIZE: Final = 8192
#: Image rows drawn at a time (bounds the memory of the interpolation).
_ROWS_PER_BLOCK: Final = 256
#: The Sun's photospheric radius (IAU 2015 Resolution B3 nominal value). [m]
SUN_RADIUS_M: Final = 6.957e8
#: Directions this close to the Sun are left out of the default exposure: its aureole may
#: clip, the rest of the sky may not. [deg]
EXPOSURE_SUN_EXCLUSION_DEG: Final = 10.0
#: Least samples per pixel side where a pixel meets the Sun's disc (antialiasing: 8 x 8 = 64
#: samples; more where the disc is smaller than two pixels).
_SUN_SUPERSAMPLING: Final = 8


def check_image_size(name: str, value: Any, *, minimum: int = 16, allow_large: bool = False) -> int:
    """Return an image side ``value`` [pixels], refused before any work if out of range.

    Without ``allow_large`` the side must be within ``[minimum,``
    :data:`MAX_IMAGE_SIZE` ``]``; with it, up to the side whose 8-bit RGB
    pixels fit the memory budget.

    Raises
    ------
    ValueError
        Not an integer or below ``minimum``.
    dustoptics._validation.BudgetError
        Above :data:`MAX_IMAGE_SIZE` without ``allow_large`` (or beyond the
        memory budget with it); the message names the largest allowed value.
    """
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum} pixels; got {value!r}")
    value = int(value)
    hard = math.isqrt(MEMORY_BUDGET_BYTES // 3)
    limit = hard if allow_large else MAX_IMAGE_SIZE
    if value > limit:
        hint = "" if allow_large else ", or pass allow_large=True (--allow-large) to go ahead"
        raise BudgetError(f"{name} = {value} pixels is beyond the largest allowed, {limit}{hint}")
    return value


def check_png_support() -> None:
    """Raise ImportError now if PNG images cannot be written (matplotlib or Pillow missing).

    Call it before a long computation whose results go to PNG files.
    """
    # Found, not imported: importing matplotlib takes 0.3-0.5 s, and the sky's own images
    # are written with Pillow (matplotlib's image writer, which the plot extra brings).
    if not all(_module_found(name) for name in ("matplotlib", "PIL")):
        raise ImportError(
            "writing PNG images needs matplotlib and Pillow: pip install 'dustoptics[plot]'"
        )


def _module_found(name: str) -> bool:
    """Whether ``import name`` would find the module (None in ``sys.modules``: not found)."""
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):
        return False


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
    radiance_error : numpy.ndarray, shape (n_wavelength,)
        Estimated relative error of the radiance
        (:func:`~dustoptics.sky.accuracy.radiance_error_estimate`; validated
        in :data:`~dustoptics.sky.accuracy.VALIDATED_DOMAIN`). [-]
    n_streams : int
        Discrete ordinates per hemisphere of the multiple scattering.
    sun_angular_radius_deg : float
        The Sun's angular radius seen from the planet; the images draw its
        disc (:func:`sun_disc_xyz`; :func:`sun_angular_radius_deg_of`); 0 draws none. [deg]
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
    radiance_error: np.ndarray = dataclass_field(default_factory=lambda: np.zeros(0))
    n_streams: int = 0
    sun_angular_radius_deg: float = 0.0

    @property
    def sun_elevation_deg(self) -> float:
        """The Sun's elevation, 90 - zenith angle. [deg]"""
        return 90.0 - self.sun_zenith_deg

    def at(self, view_zenith_deg: Any, view_azimuth_deg: Any) -> np.ndarray:
        """Radiance in other directions (bilinear in zenith and azimuth). [sr^-1]

        Azimuths are folded into [0, 180] by the sky's mirror symmetry.
        Returns shape ``broadcast(zenith, azimuth).shape + (n_wavelength,)``.
        """
        return self._interpolate(self.radiance, view_zenith_deg, view_azimuth_deg)

    def _interpolate(
        self, values: np.ndarray, view_zenith_deg: Any, view_azimuth_deg: Any
    ) -> np.ndarray:
        # Bilinear in zenith and azimuth of values (n_zenith, n_azimuth, k).
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
        r = values
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
        """Exposure at which the brightest sky farther than
        :data:`EXPOSURE_SUN_EXCLUSION_DEG` from the Sun just reaches display white.

        The exposure is chosen from the scene: the largest linear sRGB channel
        of the computed directions outside that cone is put at 1, so no part of
        the sky away from the Sun clips (the horizon of a clear Earth sky, the
        brightest region there, keeps its colour); the aureole inside the cone
        and the Sun's disc may clip.
        """
        zz, aa = np.meshgrid(self.view_zenith_deg, self.view_azimuth_deg, indexing="ij")
        away = _angle_from_sun_deg(self.sun_zenith_deg, zz, aa) > EXPOSURE_SUN_EXCLUSION_DEG
        rgb = colour.xyz_to_linear_srgb(self.xyz()[away])
        brightest = float(np.max(rgb)) if rgb.size else 0.0
        if not brightest > 0.0:  # a black sky (the Sun far below the horizon): any exposure
            return 1.0
        return 1.0 / brightest

    def fisheye(
        self, *, size: int = 512, exposure: float | None = None, allow_large: bool = False
    ) -> np.ndarray:
        """Display sRGB fisheye image (equidistant; zenith centre, horizon rim).

        The Sun's azimuth points up in the image.  Pixels outside the horizon
        circle are black.  The sky's XYZ (linear in the radiance) is
        interpolated to the pixels, a block of rows at a time.

        Parameters
        ----------
        size : int
            Image side, 16 .. :data:`MAX_IMAGE_SIZE` (:func:`check_image_size`). [pixels]
        exposure : float, optional
            Display white at ``Y * exposure = 1`` (default :meth:`default_exposure`).
        allow_large : bool
            Allow a side beyond :data:`MAX_IMAGE_SIZE`.

        Returns
        -------
        numpy.ndarray, shape (size, size, 3), dtype uint8
        """
        size = check_image_size("size", size, allow_large=allow_large)
        e = self.default_exposure() if exposure is None else check_positive("exposure", exposure)
        xyz = self.xyz()
        c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
        out = np.zeros((size, size, 3), dtype=np.uint8)

        def direction(z: np.ndarray, a: np.ndarray, du: float, dv: float) -> tuple[Any, Any]:
            # Sub-pixel offsets (du, dv pixels) in the image plane: x = (zen / 90) sin(azi),
            # y = (zen / 90) cos(azi), one pixel 2 / size; rows go down.
            x = z / 90.0 * np.sin(np.radians(a)) + du * 2.0 / size
            y = z / 90.0 * np.cos(np.radians(a)) - dv * 2.0 / size
            return np.minimum(np.hypot(x, y) * 90.0, 90.0), np.degrees(np.arctan2(x, y))

        for start in range(0, size, _ROWS_PER_BLOCK):
            xx, yy = np.meshgrid(c, -c[start : start + _ROWS_PER_BLOCK])
            rad = np.hypot(xx, yy)
            inside = rad <= 1.0
            zen = np.where(inside, rad * 90.0, 0.0)
            azi = np.rad2deg(np.arctan2(xx, yy))
            block = self._interpolate(xyz, zen, azi)
            block += self._sun_in_pixels(zen, azi, 180.0 / size, direction)
            rgb = display_rgb(block, e)
            rgb[~inside] = 0
            out[start : start + rgb.shape[0]] = rgb
        return out

    def _sun_in_pixels(
        self,
        zen: np.ndarray,
        azi: np.ndarray,
        pixel_deg: float,
        direction: Any,
    ) -> np.ndarray:
        """The Sun's disc, averaged over each pixel (XYZ to add to the sky's).

        Only pixels within a pixel's reach of the disc are sampled, each on a
        grid of at least 8 x 8 sub-pixel directions and at least 16 across the
        disc (``direction(zen, azi, du, dv)`` gives them), so the disc's edge
        is antialiased and its light kept (tested to 1 %).
        """
        out = np.zeros(zen.shape + (3,))
        alpha = self.sun_angular_radius_deg
        if alpha <= 0.0 or self.sun_zenith_deg >= 90.0 + alpha:
            return out
        near = _angle_from_sun_deg(self.sun_zenith_deg, zen, azi) <= alpha + 1.5 * pixel_deg
        if not np.any(near):
            return out
        # At least 8 x 8 samples a pixel, and at least 16 across the disc's diameter.
        k = min(4 * _SUN_SUPERSAMPLING, max(_SUN_SUPERSAMPLING, math.ceil(8.0 * pixel_deg / alpha)))
        offsets = (np.arange(k) + 0.5) / k - 0.5
        total = np.zeros((int(near.sum()), 3))
        centre = sunlit_xyz(self.wavelength_nm, np.asarray(self.sun_transmittance, dtype=float))
        for du in offsets:
            for dv in offsets:
                z, a = direction(zen[near], azi[near], du, dv)
                psi = _angle_from_sun_deg(self.sun_zenith_deg, z, a)
                total += _limb_darkening(psi, alpha)[..., None] * centre
        out[near] = total / (k * k)
        return out

    def panorama(
        self,
        *,
        width: int = 1024,
        height: int = 256,
        exposure: float | None = None,
        allow_large: bool = False,
    ) -> np.ndarray:
        """Display sRGB panorama: azimuth -180..180 (Sun at the centre), elevation 0..90.

        Returns
        -------
        numpy.ndarray, shape (height, width, 3), dtype uint8
        """
        width = check_image_size("width", width, minimum=8, allow_large=allow_large)
        height = check_image_size("height", height, minimum=8, allow_large=allow_large)
        e = self.default_exposure() if exposure is None else check_positive("exposure", exposure)
        xyz = self.xyz()
        azi = (np.arange(width) + 0.5) / width * 360.0 - 180.0
        elev = 90.0 - (np.arange(height) + 0.5) / height * 90.0
        out = np.zeros((height, width, 3), dtype=np.uint8)
        pixel_deg = max(360.0 / width, 90.0 / height)

        def direction(z: np.ndarray, a: np.ndarray, du: float, dv: float) -> tuple[Any, Any]:
            return np.clip(z + dv * 90.0 / height, 0.0, 90.0), a + du * 360.0 / width

        for start in range(0, height, _ROWS_PER_BLOCK):
            aa, ee = np.meshgrid(azi, elev[start : start + _ROWS_PER_BLOCK])
            block = self._interpolate(xyz, 90.0 - ee, aa)
            block += self._sun_in_pixels(90.0 - ee, aa, pixel_deg, direction)
            out[start : start + aa.shape[0]] = display_rgb(block, e)
        return out

    def to_xarray(self) -> Any:
        """The sky as an ``xarray.Dataset`` (radiance, XYZ, chromaticity)."""
        import xarray as xr  # lazy: xarray adds 0.7-1 s to start-up (-X importtime)

        data, coords, attrs = self.dataset_variables()
        return xr.Dataset(data, coords=coords, attrs=attrs)

    def netcdf_bytes(self, attrs: Mapping[str, Any] | None = None) -> bytes:
        """The classic netCDF file of :meth:`to_xarray`'s dataset with ``attrs`` added to its
        global attributes: the bytes of its ``to_netcdf(engine="scipy")``, without xarray
        (:func:`dustoptics.sky._netcdf.netcdf3_bytes`)."""
        data, coords, own = self.dataset_variables()
        return netcdf3_bytes(data, coords, {**own, **(attrs or {})})

    def dataset_variables(
        self,
    ) -> tuple[dict[str, Variable], dict[str, Variable], dict[str, Any]]:
        """The data variables, coordinates and attributes of :meth:`to_xarray`'s dataset.

        Returns
        -------
        data, coords : dict
            Name -> (dimensions, values, attributes), in the dataset's order.
        attrs : dict
            The global attributes.
        """
        xyz = self.xyz()
        dims = ("view_zenith_angle", "view_azimuth_angle")
        return (
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
                **(
                    {
                        "radiance_relative_error": (
                            ("wavelength",),
                            self.radiance_error,
                            {
                                "units": "1",
                                "long_name": "estimated relative error of the radiance",
                                "comment": "dustoptics.sky.accuracy.radiance_error_estimate: "
                                "1e-3 + c(n_streams) sqrt(tau_f) + the orders' remainder; "
                                f"validated against CDISORT for {VALIDATED_DOMAIN}",
                            },
                        )
                    }
                    if self.radiance_error.size == self.wavelength_nm.size
                    else {}
                ),
            },
            {
                "view_zenith_angle": (
                    ("view_zenith_angle",),
                    self.view_zenith_deg,
                    {"units": "degree"},
                ),
                "view_azimuth_angle": (
                    ("view_azimuth_angle",),
                    self.view_azimuth_deg,
                    {"units": "degree", "long_name": "azimuth from the Sun's"},
                ),
                "wavelength": (("wavelength",), self.wavelength_nm, {"units": "nm"}),
            },
            {
                "title": f"sky of {self.name}",
                "sun_zenith_angle_degree": self.sun_zenith_deg,
                "observer_altitude_m": self.observer_altitude_m,
                "orders_of_scattering": self.n_orders,
                "orders_error_estimate": self.error_estimate,
                "orders_tolerance": self.tol,
                "n_streams": self.n_streams,
                "sun_angular_radius_degree": self.sun_angular_radius_deg,
                "radiance_relative_error_max": float(np.max(self.radiance_error))
                if self.radiance_error.size
                else float("nan"),
                "radiance_error_domain": VALIDATED_DOMAIN,
                "illuminant": "ASTM G-173 extraterrestrial (shape), CIE 1931 2-degree observer",
            },
        )


def sunlit_xyz(wavelength_nm: np.ndarray, spectra: np.ndarray) -> np.ndarray:
    """CIE 1931 XYZ of radiances under sunlight, per unit solar illuminance. [sr^-1]

    ``spectra`` has the wavelengths last; ``Y`` is the luminance factor.
    """
    sun = colour.spectrum_to_xyz(wavelength_nm, np.ones(wavelength_nm.size), illuminant=ILLUMINANT)
    return colour.spectrum_to_xyz(wavelength_nm, spectra, illuminant=ILLUMINANT) / sun[1]


def sun_angular_radius_deg_of(sun_distance_m: float) -> float:
    """The Sun's angular radius seen from ``sun_distance_m``: asin(R_sun / d). [deg]"""
    d = check_positive("sun_distance_m", sun_distance_m, unit="m")
    return math.degrees(math.asin(min(1.0, SUN_RADIUS_M / d)))


def sun_disc_xyz(
    wavelength_nm: np.ndarray,
    sun_transmittance: np.ndarray,
    angle_from_centre_deg: Any,
    *,
    sun_angular_radius_deg: float,
) -> np.ndarray:
    """CIE XYZ of the Sun's disc seen through the atmosphere, per unit solar illuminance. [sr^-1]

    The disc's radiance at angle ``psi`` from its centre follows the grey
    limb darkening of the Eddington approximation (Eddington 1926; Mihalas
    1978, Stellar Atmospheres, Eq. 3-23):

        I(mu) / I(1) = (2 + 3 mu) / 5,   mu = sqrt(1 - (sin psi / sin alpha)^2),

    normalized so that its integral over the disc is the transmitted beam
    (the mean of (2 + 3 mu) / 5 over the disc's area is 4/5):

        I(1) = T(lambda) / (0.8 pi sin^2 alpha).

    Grey: the real limb is also redder (the law leaves the colour alone).
    Zero outside the disc.

    Parameters
    ----------
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        Wavelengths. [nm]
    sun_transmittance : numpy.ndarray, shape (n_wavelength,)
        Transmittance of the direct beam to the observer. [-]
    angle_from_centre_deg : array_like
        Angle of each direction from the disc's centre. [deg]
    sun_angular_radius_deg : float
        The disc's angular radius (:func:`sun_angular_radius_deg_of`). [deg]

    Returns
    -------
    numpy.ndarray, shape ``angle_from_centre_deg.shape + (3,)``
    """
    darkening = _limb_darkening(angle_from_centre_deg, sun_angular_radius_deg)
    centre = sunlit_xyz(wavelength_nm, np.asarray(sun_transmittance, dtype=float))
    return darkening[..., None] * centre


def _limb_darkening(angle_from_centre_deg: Any, sun_angular_radius_deg: float) -> np.ndarray:
    """:func:`sun_disc_xyz`'s disc radiance over the transmitted beam's, ``(2 + 3 mu) /
    (4 pi sin^2 alpha)`` inside the disc, 0 outside. [sr^-1]"""
    psi = np.asarray(angle_from_centre_deg, dtype=float)
    sin_a = math.sin(math.radians(sun_angular_radius_deg))
    r = np.sin(np.radians(np.minimum(psi, 90.0))) / sin_a
    inside = (psi < sun_angular_radius_deg) & (r < 1.0)
    mu = np.sqrt(np.clip(1.0 - r * r, 0.0, 1.0))
    return np.where(inside, (2.0 + 3.0 * mu) / 5.0, 0.0) / (0.8 * math.pi * sin_a * sin_a)


def _angle_from_sun_deg(sun_zenith_deg: float, zenith_deg: Any, azimuth_deg: Any) -> np.ndarray:
    """Angle between each view direction and the Sun (azimuths from the Sun's). [deg]"""
    z, a, s = np.radians(zenith_deg), np.radians(azimuth_deg), math.radians(sun_zenith_deg)
    cos_psi = np.cos(z) * math.cos(s) + np.sin(z) * math.sin(s) * np.cos(a)
    return np.degrees(np.arccos(np.clip(cos_psi, -1.0, 1.0)))


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
    sun_angular_radius_deg: float | None = None,
    progress: TextIO | Reporter | None = None,
    allow_large: bool = False,
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
    sun_angular_radius_deg : float, optional
        The Sun's angular radius, for its disc in the images (default: from
        the atmosphere's ``sun_distance_m``, :func:`sun_angular_radius_deg`;
        0, no disc, for a Medium, which does not know it). [deg]
    progress : text stream, optional
        Where to report the orders of scattering and the lines of sight done,
        after the first two seconds (the command line passes ``sys.stderr``);
        None is silent.
    allow_large : bool
        Go ahead beyond the memory and work budget of the orders and of the
        lines of sight (both checked before any work).

    Returns
    -------
    SkyRadiance

    Raises
    ------
    dustoptics._validation.BudgetError
        The orders or the lines of sight would need more memory or work than
        the budget and ``allow_large`` is False (the message names the
        parameter and its largest allowed value).
    """
    if sun_angular_radius_deg is None:
        alpha = (
            sun_angular_radius_deg_of(atmosphere.sun_distance_m)
            if isinstance(atmosphere, Atmosphere)
            else 0.0
        )
    else:
        alpha = check_closed_interval("sun_angular_radius_deg", sun_angular_radius_deg, 0.0, 45.0)
    report = reporter(progress)
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
    # Both budgets before any work.
    if field is None:
        check_orders_cost(medium, n_layers=N_LAYERS, tol=tol, allow_large=allow_large)
    check_render_cost(
        medium,
        n_rays=zen.size * azi.size,
        n_rows=zen.size,
        n_path=N_PATH,
        allow_large=allow_large,
        what="view_zenith_deg x azimuth_step_deg",
    )
    if field is None:
        field = solve_orders(
            medium,
            sun_zenith_deg=90.0 - elev,
            ground_albedo=ground_albedo,
            tol=tol,
            progress=report,
            allow_large=allow_large,
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
        progress=report,
        allow_large=allow_large,
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
        radiance_error=radiance_error_estimate(
            medium, field, observer_altitude_m=float(observer_altitude_m)
        ),
        n_streams=medium.n_streams,
        sun_angular_radius_deg=float(alpha),
    )


def png_bytes(rgb: np.ndarray) -> bytes:
    """PNG file contents of an 8-bit RGB image, without time stamps (same bytes each time).

    Needs the ``plot`` extra (matplotlib).
    """
    check_png_support()
    rgb = np.asarray(rgb)
    buf = _io.BytesIO()
    if rgb.dtype != np.uint8 or rgb.ndim != 3 or rgb.shape[2] != 3:
        import matplotlib.image  # lazy: 0.3-0.5 s (-X importtime)

        no_stamp: dict[str, Any] = {"Software": None}  # same bytes on every run
        matplotlib.image.imsave(buf, rgb, format="png", metadata=no_stamp)
        return buf.getvalue()
    # The bytes matplotlib.image.imsave writes for 8-bit RGB (an opaque RGBA image, no text
    # chunk, 100 dpi), without importing matplotlib.
    from PIL import Image, PngImagePlugin  # lazy: the plot extra's

    height, width = int(rgb.shape[0]), int(rgb.shape[1])
    rgba = np.empty((height, width, 4), dtype=np.uint8)
    rgba[..., :3] = rgb
    rgba[..., 3] = 255
    image = Image.frombuffer("RGBA", (width, height), rgba, "raw", "RGBA", 0, 1)
    image.save(buf, format="png", pnginfo=PngImagePlugin.PngInfo(), dpi=(100, 100))
    return buf.getvalue()
