"""A sky as a high-dynamic-range environment map for renderers (image-based lighting).

:func:`environment_map` turns a computed sky (:class:`~dustoptics.sky.scene.SkyRadiance`)
into a linear, scene-referred, equirectangular RGB image in absolute units:

- **Units**: luminance in candela per square metre [cd m^-2].  The sky's
  luminance factor (its radiance weighted by the solar spectrum and CIE 1931
  ybar, per unit solar illuminance; :func:`~dustoptics.sky.scene.sunlit_xyz`)
  times the Sun's illuminance at the top of the planet's atmosphere
  (:func:`solar_illuminance_lux`).  The OpenEXR files store kilocandela per
  square metre: RGB (1, 1, 1) has a luminance of 1000 cd m^-2 (the OpenEXR
  attribute ``whiteLuminance``, :data:`EXR_WHITE_LUMINANCE_CD_M2`).
- **Primaries**: linear Rec. ITU-R BT.709 / sRGB, D65 white (the OpenEXR
  attribute ``chromaticities``): the scene-linear space of Blender, Unity,
  Unreal, Godot and three.js.  Colours outside the gamut keep their negative
  components (scene-referred; nothing is clipped).
- **Layout**: width = 2 x height; the top row looks at the zenith, the bottom
  row at the nadir; the centre column looks toward the Sun's azimuth (the
  +X axis of Blender's and three.js's equirectangular mapping) and longitude
  runs over the full circle.  The sky is mirror-symmetric about the Sun's
  vertical plane, so the direction in which longitude increases does not matter.
- **The lower hemisphere** is the Lambertian ground the sky was computed
  with: radiance ``albedo / pi * (mu0 T_sun + integral of L cos(theta) dOmega)``
  per unit solar irradiance, the same in every downward direction.
- **The Sun's disc is not in the map**: its luminance (about 1e9 cd m^-2)
  overflows half floats and image-based lighting samples it badly.  Renderers
  add it as a directional light: its direction and its illuminance at the
  observer (the transmitted beam, normal to it) are in the map's metadata.

:func:`exr_bytes` encodes the map as OpenEXR (half or float, through the
package's OpenEXR writer :func:`dustoptics.io.textures.exr.encode_exr`);
:func:`cubemap` resamples it onto the six faces of a cube (a 6 x 1 strip).

References
----------
.. [1] Academy Software Foundation, "OpenEXR: Technical Introduction", standard
   attributes ``chromaticities`` and ``whiteLuminance``,
   https://openexr.com/en/latest/TechnicalIntroduction.html.
.. [2] ASTM G173-03, extraterrestrial spectrum (the package's solar table).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from dustoptics import colour
from dustoptics._validation import check_choice, check_positive
from dustoptics.io.textures.exr import encode_exr
from dustoptics.sky.scene import SkyRadiance, check_image_size, sunlit_xyz

__all__ = [
    "ASTRONOMICAL_UNIT_M",
    "CUBE_FACES",
    "EXR_PRECISIONS",
    "EXR_WHITE_LUMINANCE_CD_M2",
    "EnvironmentMap",
    "cubemap",
    "direction_of_pixels",
    "environment_map",
    "exr_bytes",
    "solar_illuminance_lux",
]

#: The astronomical unit (IAU 2012 Resolution B2, exact). [m]
ASTRONOMICAL_UNIT_M: Final = 149_597_870_700.0

#: OpenEXR pixel types the maps are written in: 16-bit half or 32-bit float.
EXR_PRECISIONS: Final = ("half", "float")

#: Luminance of the OpenEXR pixel value 1 (its ``whiteLuminance``): the files hold kcd m^-2, so
#: a Mars or Earth sky fits half floats (the Mars aureole reaches 2.5e5 cd m^-2). [cd m^-2]
EXR_WHITE_LUMINANCE_CD_M2: Final = 1000.0

#: Faces of :func:`cubemap`, left to right in its 6 x 1 strip (Y up, OpenGL's cube-map
#: convention: OpenGL 4.6 core specification, section 8.13, table 8.19).
CUBE_FACES: Final = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")

#: Rec. ITU-R BT.709 (sRGB) primaries and D65 white, CIE 1931 xy: red, green, blue, white.
_REC709_CHROMATICITIES: Final = (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290)

#: Rows of the map interpolated at once (memory: rows x width x 3 x 8 bytes per array).
_ROWS_PER_BLOCK: Final = 64


def solar_illuminance_lux(*, sun_distance_m: float) -> float:
    """The Sun's illuminance at the top of an atmosphere ``sun_distance_m`` from it. [lx]

    ``683 lm/W * integral of E(lambda) ybar(lambda) d lambda`` over 360-830 nm
    (the ASTM G173-03 extraterrestrial spectrum at 1 au, CIE 1931 ybar, 1 nm
    steps, trapezoidal), scaled by ``(1 au / d)^2``: 133,121 lx at 1 au.

    Parameters
    ----------
    sun_distance_m : float
        Distance from the Sun. [m]

    Returns
    -------
    float
        Illuminance on a surface normal to the beam. [lx]
    """
    d = check_positive("sun_distance_m", sun_distance_m, unit="m")
    lam = np.arange(360.0, 830.5, 1.0)
    ybar = colour.cmf_cie1931(lam)[:, 1]
    at_1au = colour.MAX_LUMINOUS_EFFICACY_LM_PER_W * float(
        np.trapezoid(colour.solar_irradiance_astm_g173(lam) * ybar, lam)
    )
    return at_1au * (ASTRONOMICAL_UNIT_M / d) ** 2


@dataclass(frozen=True, eq=False)
class EnvironmentMap:
    """An equirectangular, scene-linear environment map of a sky (see the module's notes).

    Attributes
    ----------
    rgb : numpy.ndarray, shape (height, width, 3), float64
        Linear Rec. 709 RGB, luminance ``Y = 0.2126 R + 0.7152 G + 0.0722 B``. [cd m^-2]
    sun_elevation_deg : float
        The Sun's elevation; its azimuth is the centre column's. [deg]
    sun_illuminance_lux : float
        The direct Sun's illuminance at the observer, normal to the beam (not in the map). [lx]
    sun_rgb : numpy.ndarray, shape (3,)
        The direct Sun's illuminance as linear Rec. 709 RGB (its luminance is
        ``sun_illuminance_lux``). [lx]
    top_of_atmosphere_lux : float
        The Sun's illuminance at the top of the atmosphere, the unit of the
        sky's luminance factor (:func:`solar_illuminance_lux`). [lx]
    exposure : float
        The display exposure of the sky's PNG images, in the map's units: a
        pixel of luminance ``1 / exposure`` is display white. [cd^-1 m^2]
    ground_luminance_cd_m2 : float
        Luminance of the lower hemisphere (the Lambertian ground). [cd m^-2]
    name : str
        The atmosphere's name.
    """

    rgb: np.ndarray
    sun_elevation_deg: float
    sun_illuminance_lux: float
    sun_rgb: np.ndarray
    top_of_atmosphere_lux: float
    exposure: float
    ground_luminance_cd_m2: float
    name: str

    def metadata(self) -> dict[str, Any]:
        """What the map holds, its units, layout and the Sun left out (JSON-serializable)."""
        h, w = self.rgb.shape[:2]
        return {
            "what": f"equirectangular sky environment map of {self.name}",
            "units": "cd m-2 (luminance of RGB (1,1,1) = 1 cd m-2)",
            "primaries": "Rec. ITU-R BT.709 / sRGB, D65 white, linear (scene-referred)",
            "layout": (
                f"equirectangular {w} x {h}: top row zenith, bottom row nadir, centre column "
                "toward the Sun's azimuth (+X of Blender's and three.js's equirectangular "
                "mapping); lower hemisphere: the Lambertian ground"
            ),
            "sun_in_map": False,
            "sun_elevation_deg": self.sun_elevation_deg,
            "sun_azimuth": "the centre column's",
            "sun_illuminance_lux": self.sun_illuminance_lux,
            "sun_rgb_lux": [float(v) for v in self.sun_rgb],
            "top_of_atmosphere_illuminance_lux": self.top_of_atmosphere_lux,
            "exposure_per_cd_m2": self.exposure,
            "ground_luminance_cd_m2": self.ground_luminance_cd_m2,
            "illuminant": "ASTM G173 extraterrestrial spectrum, CIE 1931 2-degree observer",
            "software": "dustoptics (dustoptics.sky.hdr.environment_map)",
        }


def direction_of_pixels(height: int) -> tuple[np.ndarray, np.ndarray]:
    """Elevation of each row and longitude from the Sun's azimuth of each column (centres).

    Parameters
    ----------
    height : int
        Map height; the width is ``2 * height``. [pixels]

    Returns
    -------
    elevation_deg : numpy.ndarray, shape (height,)
        ``90 - 180 (i + 0.5) / height``: +90 at the top. [deg]
    longitude_deg : numpy.ndarray, shape (2 * height,)
        ``360 (j + 0.5) / width - 180``: 0 at the centre (the Sun's azimuth). [deg]
    """
    width = 2 * height
    elevation = 90.0 - 180.0 * (np.arange(height) + 0.5) / height
    longitude = 360.0 * (np.arange(width) + 0.5) / width - 180.0
    return elevation, longitude


def _ground_radiance(sky: SkyRadiance) -> np.ndarray:
    """Lambertian ground radiance per unit solar irradiance, per wavelength. [sr^-1]

    ``albedo / pi * (mu0 T_sun + 2 int_0^pi int_0^(pi/2) L cos(z) sin(z) dz da)``:
    the sky's azimuths cover 0..180 deg (mirror symmetry), trapezoidal in both.
    """
    z = np.radians(sky.view_zenith_deg)
    a = np.radians(sky.view_azimuth_deg)
    weights = (np.cos(z) * np.sin(z))[:, None, None]
    over_azimuth = np.trapezoid(sky.radiance * weights, a, axis=1)
    diffuse = 2.0 * np.trapezoid(over_azimuth, z, axis=0)
    mu0 = max(math.cos(math.radians(sky.sun_zenith_deg)), 0.0)
    return np.asarray(sky.ground_albedo) / math.pi * (mu0 * sky.sun_transmittance + diffuse)


def environment_map(
    sky: SkyRadiance,
    *,
    sun_distance_m: float,
    height: int = 512,
    exposure: float | None = None,
    allow_large: bool = False,
) -> EnvironmentMap:
    """The sky as a linear, equirectangular environment map in cd m^-2 (the module's notes).

    Each pixel is the sky's XYZ at its centre direction (bilinear in the sky's
    zenith-azimuth grid, as the PNG images), converted to linear Rec. 709 and
    scaled by the top-of-atmosphere illuminance.

    Parameters
    ----------
    sky : SkyRadiance
        The computed sky.
    sun_distance_m : float
        The planet's distance from the Sun (the atmosphere's ``sun_distance_m``). [m]
    height : int, optional
        Map height, 16 .. :data:`~dustoptics.sky.scene.MAX_IMAGE_SIZE`; width
        ``2 * height``.  Default 512. [pixels]
    exposure : float, optional
        The PNG images' exposure (display white at ``Y * exposure = 1``, Y the
        luminance factor); default the sky's
        (:meth:`~dustoptics.sky.scene.SkyRadiance.default_exposure`). [sr]
    allow_large : bool, optional
        Allow a height beyond :data:`~dustoptics.sky.scene.MAX_IMAGE_SIZE`.

    Returns
    -------
    EnvironmentMap

    Raises
    ------
    ValueError
        A non-positive ``sun_distance_m`` or ``exposure``; a height out of range.
    """
    height = check_image_size("height", height, allow_large=allow_large)
    e_top = solar_illuminance_lux(sun_distance_m=sun_distance_m)
    e = sky.default_exposure() if exposure is None else check_positive("exposure", exposure)
    elevation, longitude = direction_of_pixels(height)
    xyz = sky.xyz()
    rgb = np.zeros((height, 2 * height, 3))
    up = np.flatnonzero(elevation > 0.0)
    for start in range(0, up.size, _ROWS_PER_BLOCK):
        rows = up[start : start + _ROWS_PER_BLOCK]
        zz, aa = np.meshgrid(90.0 - elevation[rows], longitude, indexing="ij")
        rgb[rows] = colour.xyz_to_linear_srgb(sky._interpolate(xyz, zz, aa))
    ground_xyz = sunlit_xyz(sky.wavelength_nm, _ground_radiance(sky))
    rgb[elevation < 0.0] = colour.xyz_to_linear_srgb(ground_xyz)
    sun_xyz = sunlit_xyz(sky.wavelength_nm, np.asarray(sky.sun_transmittance, dtype=float))
    return EnvironmentMap(
        rgb=rgb * e_top,
        sun_elevation_deg=sky.sun_elevation_deg,
        sun_illuminance_lux=float(sun_xyz[1]) * e_top,
        sun_rgb=colour.xyz_to_linear_srgb(sun_xyz) * e_top,
        top_of_atmosphere_lux=e_top,
        exposure=e / e_top,
        ground_luminance_cd_m2=float(ground_xyz[1]) * e_top,
        name=sky.name,
    )


def _cube_directions(size: int) -> np.ndarray:
    """Unit directions (6, size, size, 3) of the texel centres of each face (x, y, z; Y up).

    OpenGL's table 8.19: face +X (sc, tc, ma) = (-rz, -ry, rx), -X (rz, -ry, -rx),
    +Y (rx, rz, ry), -Y (rx, -rz, -ry), +Z (rx, -ry, rz), -Z (-rx, -ry, -rz), with
    s = (sc / |ma| + 1) / 2 across a row and t likewise down the rows.
    """
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    tc, sc = np.meshgrid(c, c, indexing="ij")
    one = np.ones_like(sc)
    faces = [
        (one, -tc, -sc),  # +X
        (-one, -tc, sc),  # -X
        (sc, one, tc),  # +Y
        (sc, -one, -tc),  # -Y
        (sc, -tc, one),  # +Z
        (-sc, -tc, -one),  # -Z
    ]
    d = np.stack([np.stack(f, axis=-1) for f in faces])
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def cubemap(env: EnvironmentMap, *, size: int | None = None) -> np.ndarray:
    """The map on the six faces of a cube, as a 6 x 1 strip (:data:`CUBE_FACES` left to right).

    Y is up and the Sun's azimuth is +X (the map's centre column); each texel
    takes the map's value in its centre direction (bilinear; the ground is
    uniform).  Face orientations follow OpenGL's cube-map convention; the face
    order is that of the 6 x 1 strips Unity and Godot import (their face
    orientations are not checked here).

    Parameters
    ----------
    env : EnvironmentMap
    size : int, optional
        Face side; default a quarter of the map's width. [pixels]

    Returns
    -------
    numpy.ndarray, shape (size, 6 * size, 3)
        Same units and primaries as ``env.rgb``. [cd m^-2]
    """
    h, w = env.rgb.shape[:2]
    n = w // 4 if size is None else check_image_size("size", size, minimum=1)
    d = _cube_directions(n)
    elevation = np.degrees(np.arcsin(np.clip(d[..., 1], -1.0, 1.0)))
    longitude = np.degrees(np.arctan2(d[..., 2], d[..., 0]))
    # Bilinear in the map's pixel centres (longitude wraps around).
    fy = np.clip((90.0 - elevation) / 180.0 * h - 0.5, 0.0, h - 1.0)
    fx = (longitude + 180.0) / 360.0 * w - 0.5
    y0 = np.minimum(np.floor(fy).astype(int), h - 2)
    x0 = np.floor(fx).astype(int)
    ty, tx = (fy - y0)[..., None], (fx - x0)[..., None]
    x0, x1 = x0 % w, (x0 + 1) % w
    m = env.rgb
    faces = (m[y0, x0] * (1 - tx) + m[y0, x1] * tx) * (1 - ty) + (
        m[y0 + 1, x0] * (1 - tx) + m[y0 + 1, x1] * tx
    ) * ty
    return np.concatenate(list(faces), axis=1)


def exr_bytes(env: EnvironmentMap, *, precision: str = "half", cube: bool = False) -> bytes:
    """The map (or its :func:`cubemap`) as OpenEXR bytes: channels R, G, B, ZIP, scanlines.

    The pixels are ``env.rgb / 1000``: kcd m^-2.  Standard attributes
    ``chromaticities`` (Rec. 709, D65) and ``whiteLuminance`` (1000: the
    luminance of RGB (1, 1, 1) in cd m^-2), the float attribute ``exposure`` (the
    PNG images' display exposure in the file's units: a pixel of luminance
    ``1 / exposure`` is display white) and the string attribute
    ``dustoptics`` (canonical JSON: :meth:`EnvironmentMap.metadata`, the Sun left
    out of the map, its direction and illuminance).  Deterministic bytes.

    Parameters
    ----------
    env : EnvironmentMap
    precision : str, optional
        ``"half"`` (16-bit, largest value 65504) or ``"float"`` (32-bit). Default "half".
    cube : bool, optional
        The 6 x 1 cube-map strip instead of the equirectangular map.

    Raises
    ------
    ValueError
        An unknown precision, or a value beyond the half range with ``"half"``.
    """
    check_choice("precision", precision, EXR_PRECISIONS)
    pixels = (cubemap(env) if cube else env.rgb) / EXR_WHITE_LUMINANCE_CD_M2
    if precision == "half" and float(np.max(np.abs(pixels))) > float(np.finfo(np.float16).max):
        raise ValueError(
            f"precision 'half': the map reaches {float(np.max(np.abs(pixels))):.4g} kcd m-2, "
            "beyond the half-float range (65504); write precision 'float'"
        )
    meta = env.metadata() | {
        "units": "kcd m-2 (luminance of RGB (1,1,1) = whiteLuminance = 1000 cd m-2)",
        "exposure": "per kcd m-2: a pixel of luminance 1 / exposure is the PNG images' white",
    }
    if cube:
        meta["layout"] = (
            f"cube map, 6 x 1 strip of faces {', '.join(CUBE_FACES)} (OpenGL convention, Y up, "
            "the Sun's azimuth toward +X)"
        )
    dtype = np.float16 if precision == "half" else np.float32
    return encode_exr(
        {"RGB": pixels.astype(dtype)},
        attributes={
            "chromaticities": _REC709_CHROMATICITIES,
            "whiteLuminance": EXR_WHITE_LUMINANCE_CD_M2,
            "exposure": float(env.exposure) * EXR_WHITE_LUMINANCE_CD_M2,
        },
        metadata=meta,
    )
