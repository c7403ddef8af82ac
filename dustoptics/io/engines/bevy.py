"""An atmosphere as Bevy's ``ScatteringMedium`` terms and chromatic phase texture.

Read from Bevy's source at :data:`BEVY_SOURCE` (``crates/bevy_light/src/atmosphere.rs``,
``crates/bevy_pbr/src/medium.rs``, ``crates/bevy_pbr/src/atmosphere/functions.wesl``,
``crates/bevy_image/src/exr_texture_loader.rs``):

- An ``Atmosphere`` has ``inner_radius`` and ``outer_radius`` [m], ``ground_albedo``
  and a ``Handle<ScatteringMedium>``.  A ``ScatteringMedium`` is a list of
  ``ScatteringTerm { absorption: Vec3, scattering: Vec3, falloff: Falloff, phase:
  PhaseFunction }``, ``absorption`` and ``scattering`` in m^-1 (linear RGB), each
  multiplied by the falloff ``f(p)`` of the "falloff parameter" ``p`` = 1 at the
  ground, 0 at ``outer_radius``, linear in altitude.
- ``Falloff::Exponential { scale }`` is ``f(p) = (exp(-(1 - p) / s) - exp(-1 / s)) /
  (1 - exp(-1 / s))``: with ``s = H / (outer - inner)`` it is ``exp(-h / H)`` shifted
  to reach 0 at the top (relative difference ``exp(-(outer - inner) / H)``, 2e-5
  for Mars' 11.1 km under Bevy's 120 km).  ``Falloff::Tent { center, width }``,
  ``Falloff::Curve``.
- ``PhaseFunction::Rayleigh`` is ``3 (1 + mu^2) / (16 pi)``; ``PhaseFunction::Mie {
  asymmetry }`` is Henyey-Greenstein (one g for the three channels, not
  Cornette-Shanks); ``PhaseFunction::ChromaticTexture(Handle<Image>)`` is an
  ``N x 1`` ``Rgba32Float`` image read by ``extract_chromatic_phase_textures``:
  any other format is skipped without a message, and the columns become a
  ``SampleAutoCurve`` over ``[-1, 1]`` -- column ``j`` at ``mu_j = -1 + 2 j / (N -
  1)``, **the first column backscattering** (theta = 180 deg, ``mu = -1``), the
  last forward, linear interpolation in ``mu`` between columns (the opposite
  order of our ``--sampling cos`` textures, whose first column is forward).
  ``mu`` is ``neg_LdotV = dot(direction_to_light, ray_dir)``, the cosine of the
  scattering angle.  Each channel must integrate to 1 over the sphere
  (``2 pi int p dmu = 1``, Bevy's doc comment).
- ``GpuScatteringMedium`` then resamples ``scattering * phase * f(p)`` into a
  ``falloff_resolution x phase_resolution`` LUT whose row ``j`` holds
  ``mu = sign(s) (1 - (1 - |s|)^2)``, ``s = 2 (j + 0.5) / phase_resolution - 1``
  (``PHASE_MAPPING_N = 0.5``), read with a bilinear clamp-to-edge sampler
  (:func:`bevy_lut_phase` reproduces it).
- ``ExrTextureLoader`` decodes any OpenEXR to ``Rgba32Float`` (A = 1 when
  absent); the KTX2 loader takes ``VK_FORMAT_R32G32B32A32_SFLOAT``.

Files (:func:`write_bevy`; ``dustoptics build mars|earth --format bevy`` through
:mod:`dustoptics.sky.engines.bevy`):
``NAME_bevy_phase.ktx2`` and ``NAME_bevy_phase.exr`` (the texture, float32 RGBA,
first column 180 deg), ``NAME_bevy_medium.rs`` (a Rust function returning the
``ScatteringMedium`` and one returning the ``Atmosphere``) and ``NAME_bevy.json``
(the same terms in SI units, with provenance).  The texture's channels are
renormalized so that Bevy's own reading (linear in ``mu``) integrates to 1; the
factors are in the JSON and the texture's metadata.

No WGSL is written: Bevy takes the phase function as data (the texture), not
as shader source, so there is no Bevy shader of ours for naga to validate.
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.atmosphere.column import (
    DensityProfile,
    ExponentialProfile,
    FixedFractionProfile,
    PiecewiseLinearProfile,
)
from dustoptics.io._atomic import Content, FormatError, safe_stem, write_files
from dustoptics.io.engines._channels import ChannelCoefficients, channel_coefficients, lua_number
from dustoptics.io.textures.exr import _writer as _exr_writer
from dustoptics.io.textures.ktx2 import ktx2_bytes
from dustoptics.io.textures.phase_texture import PhaseTexture, phase_texture

__all__ = [
    "BEVY_SOURCE",
    "BevyMedium",
    "BevyTerm",
    "bevy_falloff",
    "bevy_files",
    "bevy_lut_phase",
    "bevy_medium",
    "bevy_phase_texture",
    "bevy_rust",
    "bevy_texture_phase",
    "read_bevy_texture_ktx2",
    "write_bevy",
]

#: The Bevy source read for this module.
BEVY_SOURCE = (
    "bevyengine/bevy 0.20.0-dev, commit 4805ca792c3e94eef07afd6fa9a2712f388c9a67 "
    "(2026-08-22): crates/bevy_light/src/atmosphere.rs, crates/bevy_pbr/src/medium.rs, "
    "crates/bevy_pbr/src/atmosphere/functions.wesl"
)

#: Columns of the phase texture by default: the width of Bevy's own Mars texture
#: (assets/textures/mars_mie_phase.ktx2, 1024 x 1).
DEFAULT_COLUMNS = 1024

#: Bevy's ``phase_resolution`` and ``falloff_resolution`` in its examples.
BEVY_LUT_RESOLUTION = 256

_PHASE_MAPPING_N = 0.5  # functions.wesl, medium.rs


def bevy_texture_phase(samples: Any, mu: Any) -> np.ndarray:
    """Bevy's reading of a chromatic phase texture at cosines ``mu``.

    ``SampleAutoCurve`` over ``[-1, 1]``: column ``j`` at ``-1 + 2 j / (N - 1)``,
    linear between columns.

    Parameters
    ----------
    samples : array_like, shape (N, channels)
        The texture's columns, first column backscattering. [sr^-1]
    mu : array_like
        Cosines of the scattering angle. [-]

    Returns
    -------
    numpy.ndarray, shape mu.shape + (channels,) [sr^-1]
    """
    s = np.asarray(samples, dtype=np.float64)
    if s.ndim != 2 or s.shape[0] < 2:
        raise ValueError(f"samples must have shape (N >= 2, channels); got {s.shape}")
    m = np.clip(np.asarray(mu, dtype=np.float64), -1.0, 1.0)
    grid = np.linspace(-1.0, 1.0, s.shape[0])
    out = np.stack([np.interp(m, grid, s[:, c]) for c in range(s.shape[1])], axis=-1)
    return np.asarray(out, dtype=np.float64)


def bevy_lut_phase(
    samples: Any, mu: Any, *, phase_resolution: int = BEVY_LUT_RESOLUTION
) -> np.ndarray:
    """The phase function as Bevy's scattering LUT gives it back at cosines ``mu``.

    ``medium.rs`` samples the texture's curve at ``phase_resolution`` rows,
    row ``j`` at ``mu_j = sign(s) (1 - (1 - |s|)^(1 / 0.5))``, ``s = 2 (j + 0.5) /
    R - 1``; ``functions.wesl`` reads it at ``v = 0.5 + 0.5 sign(mu) (1 - (1 -
    |mu|)^0.5)`` with linear filtering and clamp to edge.

    Parameters
    ----------
    samples : array_like, shape (N, channels)
        The texture's columns (first backscattering). [sr^-1]
    mu : array_like
        Cosines of the scattering angle. [-]
    phase_resolution : int
        ``ScatteringMedium::phase_resolution`` (256 in Bevy's examples).

    Returns
    -------
    numpy.ndarray, shape mu.shape + (channels,) [sr^-1]
    """
    r = int(phase_resolution)
    if r < 2:
        raise ValueError(f"phase_resolution must be >= 2; got {phase_resolution!r}")
    centres = (np.arange(r) + 0.5) / r
    s = 2.0 * centres - 1.0
    mu_rows = np.sign(s) * (1.0 - (1.0 - np.abs(s)) ** (1.0 / _PHASE_MAPPING_N))
    rows = bevy_texture_phase(samples, mu_rows)  # (r, channels)
    m = np.clip(np.asarray(mu, dtype=np.float64), -1.0, 1.0)
    v = 0.5 + 0.5 * np.sign(m) * (1.0 - (1.0 - np.abs(m)) ** _PHASE_MAPPING_N)
    # Linear filtering of texel centres, clamped to the edge texels.
    out = np.stack([np.interp(v, centres, rows[:, c]) for c in range(rows.shape[1])], axis=-1)
    return np.asarray(out, dtype=np.float64)


def bevy_falloff(p: Any, *, kind: str, scale: float = 0.0, center: float = 0.0, width: float = 0.0):
    """Bevy's ``Falloff::sample(p)`` for ``Exponential { scale }`` and ``Tent { center, width }``.

    Parameters
    ----------
    p : array_like
        Falloff parameter, 1 at the ground, 0 at the top. [-]
    kind : {"exponential", "tent", "linear"}

    Returns
    -------
    numpy.ndarray [-]
    """
    x = np.asarray(p, dtype=np.float64)
    if kind == "linear" or (kind == "exponential" and scale == 0.0):
        return x
    if kind == "exponential":
        s = -1.0 / scale
        return (np.exp((1.0 - x) * s) - math.exp(s)) / (1.0 - math.exp(s))
    if kind == "tent":
        return np.maximum(1.0 - np.abs(x - center) / (0.5 * width), 0.0)
    raise ValueError(f"kind must be 'exponential', 'tent' or 'linear'; got {kind!r}")


@dataclass(frozen=True)
class BevyTerm:
    """One ``ScatteringTerm``.

    Attributes
    ----------
    name : str
        What it is (``"molecules"``, ``"dust"``, ``"ozone"``), for comments.
    absorption_per_m, scattering_per_m : tuple of 3 floats
        ``absorption``, ``scattering`` (linear RGB) where the falloff is 1. [m^-1]
    falloff : str
        ``"exponential"``, ``"tent"`` or ``"curve"``.
    falloff_values : tuple of float
        ``(scale,)``, ``(center, width)``, or the curve's samples at ``p = 0, 1 /
        (M - 1), ..., 1`` (a ``SampleAutoCurve`` over ``[0, 1]``). [-]
    phase : str
        ``"rayleigh"``, ``"isotropic"``, ``"mie"`` (HG, ``asymmetry``) or
        ``"texture"`` (the chromatic phase texture).
    asymmetry : float
        The HG g of ``"mie"``. [-]
    """

    name: str
    absorption_per_m: tuple[float, float, float]
    scattering_per_m: tuple[float, float, float]
    falloff: str
    falloff_values: tuple[float, ...]
    phase: str
    asymmetry: float = 0.0

    def falloff_at(self, p: Any) -> np.ndarray:
        """The term's ``f(p)`` as Bevy evaluates it. [-]"""
        if self.falloff == "exponential":
            return bevy_falloff(p, kind="exponential", scale=self.falloff_values[0])
        if self.falloff == "tent":
            c, w = self.falloff_values
            return bevy_falloff(p, kind="tent", center=c, width=w)
        grid = np.linspace(0.0, 1.0, len(self.falloff_values))
        return np.interp(np.asarray(p, dtype=np.float64), grid, self.falloff_values)

    def to_dict(self) -> dict[str, Any]:
        falloff: dict[str, Any]
        if self.falloff == "exponential":
            falloff = {"Exponential": {"scale": self.falloff_values[0]}}
        elif self.falloff == "tent":
            falloff = {"Tent": {"center": self.falloff_values[0], "width": self.falloff_values[1]}}
        else:
            falloff = {"Curve": {"samples_p_0_to_1": list(self.falloff_values)}}
        phase: Any = {
            "rayleigh": "Rayleigh",
            "isotropic": "Isotropic",
            "texture": "ChromaticTexture",
        }.get(self.phase, {"Mie": {"asymmetry": self.asymmetry}})
        return {
            "name": self.name,
            "absorption": list(self.absorption_per_m),
            "scattering": list(self.scattering_per_m),
            "falloff": falloff,
            "phase": phase,
        }


@dataclass(frozen=True)
class BevyMedium:
    """A ``ScatteringMedium`` and its ``Atmosphere``.

    Attributes
    ----------
    name : str
        The atmosphere's or table's name.
    inner_radius_m, outer_radius_m : float
        ``Atmosphere::inner_radius``, ``outer_radius``. [m]
    ground_albedo : float
        ``Atmosphere::ground_albedo`` (grey). [-]
    terms : tuple of BevyTerm
    channels : dict
        What the R, G, B channels are (names, wavelengths).
    texture : PhaseTexture or None
        The chromatic phase texture of the ``"texture"`` term.
    texture_file : str
        Its file name (without suffix) beside the Rust file.
    notes : tuple of str
        Provenance and choices, for the comment block.
    """

    name: str
    inner_radius_m: float
    outer_radius_m: float
    ground_albedo: float
    terms: tuple[BevyTerm, ...]
    channels: dict[str, Any]
    texture: PhaseTexture | None
    texture_file: str
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: Bevy's names, SI units, the texture's reading rule and provenance."""
        return {
            "engine": "Bevy atmosphere (ScatteringMedium)",
            "source_read": BEVY_SOURCE,
            "name": self.name,
            "atmosphere": {
                "inner_radius": self.inner_radius_m,
                "outer_radius": self.outer_radius_m,
                "ground_albedo": [self.ground_albedo] * 3,
            },
            "units": {
                "inner_radius, outer_radius": "m",
                "absorption, scattering": "m-1 (linear RGB) where the falloff is 1",
                "falloff": "f(p), p = 1 at inner_radius, 0 at outer_radius, linear in altitude",
            },
            "channels": self.channels,
            "terms": [t.to_dict() for t in self.terms],
            "phase_texture": None
            if self.texture is None
            else {
                "files": [f"{self.texture_file}.ktx2", f"{self.texture_file}.exr"],
                **{
                    k: self.texture.metadata[k]
                    for k in ("sampling_rule", "width", "sphere_integral_of_samples")
                },
                "renormalization": self.texture.metadata.get("bevy_renormalization"),
            },
            "notes": list(self.notes),
        }


def bevy_phase_texture(
    table: Any,
    *,
    n_columns: int = DEFAULT_COLUMNS,
    channels_nm: Any = None,
    colour: str | None = None,
) -> PhaseTexture:
    """The chromatic phase texture in Bevy's column order (first column 180 deg).

    The RGB ``cos`` texture of :func:`~dustoptics.io.textures.phase_texture.phase_texture`
    with its columns reversed, each channel then scaled so that Bevy's reading
    (linear in ``mu``, :func:`bevy_texture_phase`) integrates to 1 over the sphere
    (the trapezoid rule in ``mu``, exact for that reading); the factors are
    recorded (``bevy_renormalization``).  float32 RGB; the containers add A = 1.

    Parameters
    ----------
    table : dustoptics.table.Table
    n_columns : int
        Texture width ``N`` (>= 2; default 1024, as Bevy's Mars texture).
    channels_nm, colour
        The channels (:func:`dustoptics.io.shaders.common.choose_channels`).

    Returns
    -------
    PhaseTexture
        ``theta_deg`` and ``mu`` in the texture's column order (``mu`` increasing).
    """
    base = phase_texture(
        table,
        layout="rgb",
        sampling="cos",
        n_angles=n_columns,
        precision="float32",
        channels_nm=channels_nm,
        colour=colour,
    )
    rows = base.pixels[0, ::-1, :].astype(np.float64)  # (N, 3), mu increasing
    mu = np.linspace(-1.0, 1.0, n_columns)
    integral = 2.0 * math.pi * np.sum(0.5 * (rows[1:] + rows[:-1]) * np.diff(mu)[:, None], axis=0)
    scaled = rows / integral[None, :]
    pixels = np.ascontiguousarray(scaled.astype(np.float32)[None, :, :])
    pixels.setflags(write=False)
    stored = pixels[0].astype(np.float64)
    after = 2.0 * math.pi * np.sum(0.5 * (stored[1:] + stored[:-1]) * np.diff(mu)[:, None], axis=0)
    theta = np.degrees(np.arccos(mu))
    meta = dict(base.metadata)
    meta.update(
        {
            "sampling": "cos",
            "sampling_rule": (
                f"Bevy's PhaseFunction::ChromaticTexture: column j (0..{n_columns - 1}) at "
                f"mu_j = -1 + 2 j / {n_columns - 1}, mu = cos(theta); the FIRST column is "
                "backscattering (theta = 180 deg), the last forward; linear in mu between "
                "columns (SampleAutoCurve over [-1, 1])"
            ),
            "sphere_integral_of_samples": after.tolist(),
            "bevy_renormalization": {
                "sphere_integral_before": integral.tolist(),
                "rule": "each channel divided by its sphere integral read linearly in mu",
            },
            "axes": {
                "columns": {
                    "name": "mu",
                    "unit": "1",
                    "values": mu.tolist(),
                    "theta_deg": theta.tolist(),
                },
                "rows": meta["axes"]["rows"],
            },
            "engine": BEVY_SOURCE,
        }
    )
    return replace(base, pixels=pixels, theta_deg=theta, mu=mu, metadata=meta)


def read_bevy_texture_ktx2(path: str | os.PathLike[str]) -> np.ndarray:
    """The columns of an uncompressed ``R32G32B32A32_SFLOAT`` 2-D KTX2 texture, as Bevy reads them.

    Reads the header's vkFormat, size and level 0 (Khronos KTX 2.0, section 3);
    works on Bevy's own ``mars_mie_phase.ktx2`` and on ours.

    Returns
    -------
    numpy.ndarray, shape (width, 4)
        Row 0 of the image, float32 RGBA, first column first.

    Raises
    ------
    dustoptics.io.FormatError
        Not such a file.
    """
    p = Path(path)
    data = p.read_bytes()
    if len(data) < 104 or data[:12] != b"\xabKTX 20\xbb\r\n\x1a\n":
        raise FormatError(f"{str(p)!r}: not a KTX2 file")
    vk_format, _type_size, width, height = np.frombuffer(data[12:28], dtype="<u4")
    supercompression = int(np.frombuffer(data[44:48], dtype="<u4")[0])
    if int(vk_format) != 109 or supercompression != 0:
        raise FormatError(
            f"{str(p)!r}: vkFormat {int(vk_format)}, supercompression {supercompression}; Bevy's "
            "chromatic phase texture is R32G32B32A32_SFLOAT (109), uncompressed"
        )
    offset, length = (int(v) for v in np.frombuffer(data[80:96], dtype="<u8"))
    rows = max(int(height), 1)
    if offset + length > len(data) or length != 16 * int(width) * rows:
        raise FormatError(f"{str(p)!r}: level 0 does not fit its size (damaged)")
    image = np.frombuffer(data[offset : offset + length], dtype="<f4").reshape(rows, int(width), 4)
    return np.array(image[0], dtype=np.float32)


def _profile_falloff(profile: DensityProfile, height_m: float) -> tuple[str, tuple[float, ...]]:
    """Bevy's falloff of a density profile over an atmosphere of ``height_m``."""
    if isinstance(profile, FixedFractionProfile):
        return _profile_falloff(profile.base, height_m)
    if isinstance(profile, ExponentialProfile):
        return "exponential", (profile.scale_height_m / height_m,)
    if isinstance(profile, PiecewiseLinearProfile):
        z = np.asarray(profile.altitude_m, dtype=np.float64)
        d = np.asarray(profile.density, dtype=np.float64)
        nz = np.flatnonzero(d > 0.0)
        if (
            nz.size == 1
            and d[nz[0]] == 1.0
            and 0 < nz[0] < z.size - 1
            and d[nz[0] - 1] == 0.0
            and d[nz[0] + 1] == 0.0
            and math.isclose(z[nz[0]] - z[nz[0] - 1], z[nz[0] + 1] - z[nz[0]], rel_tol=1e-12)
        ):
            half = float(z[nz[0]] - z[nz[0] - 1])
            return "tent", (1.0 - float(z[nz[0]]) / height_m, 2.0 * half / height_m)
    p = np.linspace(0.0, 1.0, 257)
    return "curve", tuple(float(v) for v in profile.relative_density((1.0 - p) * height_m))


def _term(
    name: str,
    coefficients: ChannelCoefficients | None,
    table: Any,
    profile: Any,
    height_m: float,
    phase: str,
    channels_nm: Any,
    colour: str | None,
) -> BevyTerm:
    c = coefficients or channel_coefficients(table, channels_nm=channels_nm, colour=colour)
    falloff, values = _profile_falloff(profile, height_m)
    sca = tuple(float(v) for v in c.scattering_per_m)
    ab = tuple(float(v) for v in c.absorption_per_m)
    return BevyTerm(
        name=name,
        absorption_per_m=(ab[0], ab[1], ab[2]),
        scattering_per_m=(sca[0], sca[1], sca[2]),
        falloff=falloff,
        falloff_values=values,
        phase=phase,
    )


def bevy_medium(
    atmosphere: Any,
    *,
    n_columns: int = DEFAULT_COLUMNS,
    channels_nm: Any = None,
    colour: str | None = None,
    ground_albedo: float = 0.1,
) -> BevyMedium:
    """Bevy's ``ScatteringMedium`` and ``Atmosphere`` for an atmosphere set.

    Molecules: ``PhaseFunction::Rayleigh`` (``3 (1 + mu^2) / (16 pi)``, without
    the depolarization our molecules' phase function has).  Aerosols (dust): ``PhaseFunction::ChromaticTexture`` of
    :func:`bevy_phase_texture`.  Ozone: absorption only, ``PhaseFunction::Isotropic``.
    Falloffs from the profiles (:func:`_profile_falloff`).

    Parameters
    ----------
    atmosphere : dustoptics.atmosphere.sets.Atmosphere
    n_columns, channels_nm, colour
        As :func:`bevy_phase_texture`.
    ground_albedo : float
        Grey ``ground_albedo`` (Bevy's Mars 0.1). [-]

    Returns
    -------
    BevyMedium
    """
    height = float(atmosphere.atmosphere_radius_m - atmosphere.planet_radius_m)
    terms = []
    texture = None
    chosen: ChannelCoefficients | None = None
    for c in atmosphere.constituents:
        coeff = channel_coefficients(c.table, channels_nm=channels_nm, colour=colour)
        if c.role == "aerosols":
            chosen = coeff
            texture = bevy_phase_texture(
                c.table, n_columns=n_columns, channels_nm=channels_nm, colour=colour
            )
        phase = {"molecules": "rayleigh", "aerosols": "texture", "ozone": "isotropic"}[c.role]
        terms.append(_term(c.role, coeff, c.table, c.profile, height, phase, channels_nm, colour))
    assert chosen is not None
    stem = safe_stem(atmosphere.name)
    return BevyMedium(
        name=atmosphere.name,
        inner_radius_m=float(atmosphere.planet_radius_m),
        outer_radius_m=float(atmosphere.atmosphere_radius_m),
        ground_albedo=float(ground_albedo),
        terms=tuple(terms),
        channels={"names": list(chosen.names), "wavelength_nm": chosen.wavelength_nm.tolist()},
        texture=texture,
        texture_file=f"{stem}_bevy_phase",
        notes=tuple(
            f"{c.role}: table {c.table.name!r}, input hash {c.table.provenance.input_hash}, "
            f"profile {c.profile!r}"
            for c in atmosphere.constituents
        ),
    )


def _vec3(values: tuple[float, float, float]) -> str:
    return "Vec3::new(" + ", ".join(lua_number(v) for v in values) + ")"


def _rust_falloff(term: BevyTerm) -> str:
    if term.falloff == "exponential":
        return f"Falloff::Exponential {{ scale: {lua_number(term.falloff_values[0])} }}"
    if term.falloff == "tent":
        c, w = term.falloff_values
        return f"Falloff::Tent {{ center: {lua_number(c)}, width: {lua_number(w)} }}"
    samples = ", ".join(lua_number(v) for v in term.falloff_values)
    return (
        "Falloff::from_curve(\n"
        "                    SampleAutoCurve::new(Interval::UNIT, [" + samples + "]).unwrap(),\n"
        "                )"
    )


def _rust_phase(term: BevyTerm) -> str:
    if term.phase == "rayleigh":
        return "PhaseFunction::Rayleigh"
    if term.phase == "isotropic":
        return "PhaseFunction::Isotropic"
    if term.phase == "texture":
        return "PhaseFunction::from_chromatic_texture(dust_phase.clone())"
    return f"PhaseFunction::Mie {{ asymmetry: {lua_number(term.asymmetry)} }}"


def _identifier(name: str) -> str:
    text = re.sub(r"[^A-Za-z0-9_]", "_", name).lower()
    return text if text and not text[0].isdigit() else f"atm_{text}"


def bevy_rust(medium: BevyMedium) -> str:
    """Rust source: ``NAME_medium(asset_server) -> ScatteringMedium`` and ``NAME_atmosphere``.

    Uses ``bevy::light::atmosphere`` as at :data:`BEVY_SOURCE`; the texture is
    loaded from ``textures/<texture_file>.ktx2`` (copy it into the assets folder;
    the ``ktx2`` cargo feature, or ``exr`` with the ``.exr`` file).
    """
    ident = _identifier(medium.name)
    width = medium.texture.width if medium.texture is not None else 0
    lines = [
        f"// dustoptics: {medium.name!r} as Bevy's ScatteringMedium and Atmosphere.",
        f"// Bevy source read: {BEVY_SOURCE}.",
        "// Units: absorption and scattering in m^-1 (linear RGB: "
        + ", ".join(
            f"{n} = {w:g} nm"
            for n, w in zip(("R", "G", "B"), medium.channels["wavelength_nm"], strict=True)
        )
        + "),",
        "// radii in m; falloff parameter p = 1 at inner_radius, 0 at outer_radius.",
        f"// Phase texture: assets/textures/{medium.texture_file}.ktx2 (Rgba32Float, {width}",
        '// x 1, first column theta = 180 deg, linear in cos(theta); needs the "ktx2" feature).',
        *[f"// {note}" for note in medium.notes],
        "use bevy::light::atmosphere::{Falloff, PhaseFunction, ScatteringMedium, ScatteringTerm};",
        "use bevy::light::Atmosphere;",
        "use bevy::math::curve::{Interval, SampleAutoCurve};",
        "use bevy::prelude::*;",
        "",
        f"pub fn {ident}_medium(asset_server: &AssetServer) -> ScatteringMedium {{",
        "    let dust_phase: Handle<Image> =",
        f'        asset_server.load("textures/{medium.texture_file}.ktx2");',
        "    ScatteringMedium::new(",
        f"        {BEVY_LUT_RESOLUTION},",
        f"        {BEVY_LUT_RESOLUTION},",
        "        [",
    ]
    for term in medium.terms:
        lines += [
            f"            // {term.name}",
            "            ScatteringTerm {",
            f"                absorption: {_vec3(term.absorption_per_m)},",
            f"                scattering: {_vec3(term.scattering_per_m)},",
            f"                falloff: {_rust_falloff(term)},",
            f"                phase: {_rust_phase(term)},",
            "            },",
        ]
    lines += [
        "        ],",
        "    )",
        f'    .with_label("{ident}_atmosphere")',
        "}",
        "",
        f"pub fn {ident}_atmosphere(medium: Handle<ScatteringMedium>) -> Atmosphere {{",
        "    Atmosphere {",
        f"        inner_radius: {lua_number(medium.inner_radius_m)},",
        f"        outer_radius: {lua_number(medium.outer_radius_m)},",
        f"        ground_albedo: Vec3::splat({lua_number(medium.ground_albedo)}),",
        "        medium,",
        "    }",
        "}",
    ]
    return "\n".join(lines) + "\n"


def bevy_files(medium: BevyMedium, out_dir: Path) -> dict[Path, Content]:
    """The four files of a medium (not written): textures, Rust, JSON."""
    stem = safe_stem(medium.name)
    texture = medium.texture
    assert texture is not None
    return {
        out_dir / f"{medium.texture_file}.ktx2": ktx2_bytes(texture),
        out_dir / f"{medium.texture_file}.exr": _exr_writer(texture),
        out_dir / f"{stem}_bevy_medium.rs": bevy_rust(medium).encode("utf-8"),
        out_dir / f"{stem}_bevy.json": (
            json.dumps(medium.to_dict(), indent=2, allow_nan=False) + "\n"
        ).encode("utf-8"),
    }


def write_bevy(
    atmosphere: Any,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    **options: Any,
) -> list[Path]:
    """Write ``NAME_bevy_phase.ktx2``, ``NAME_bevy_phase.exr``, ``NAME_bevy_medium.rs``, ``NAME_bevy.json``.

    Parameters
    ----------
    atmosphere : dustoptics.atmosphere.sets.Atmosphere
    out_dir : path
        Directory (created if missing); the files appear together or not at all.
    overwrite : bool
        Replace existing files.
    **options
        Passed to :func:`bevy_medium`.

    Returns
    -------
    list of pathlib.Path
    """
    return write_files(
        bevy_files(bevy_medium(atmosphere, **options), Path(out_dir)), overwrite=overwrite
    )
