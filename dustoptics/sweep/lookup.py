"""A sweep over effective radius as a 3-D lookup for renderers.

An engine that animates a dust storm (r_eff growing from ~1.5 to ~4 um)
needs the phase function over effective radius as well as angle.
:func:`write_lookup` turns a sweep (:func:`dustoptics.sweep.sweep`) over one
radius axis into three files:

``<stem>.raw``
    The phase function [sr^-1] as little-endian IEEE-754 float32, C order of
    an array of shape ``(n_channels, n_radii, n_angles)``, angle fastest.
    Uploaded as it is, it is a ``GL_TEXTURE_2D_ARRAY`` (or a
    ``GL_TEXTURE_3D``) of width ``n_angles``, height ``n_radii`` and
    ``n_channels`` layers, ``GL_R32F`` / ``GL_RED`` / ``GL_FLOAT``: texel
    ``(j, i, c)`` is angle sample j at radius i in channel c.
``<stem>.json``
    The sidecar: format, shape, dtype, GL upload parameters, the axes with
    their values and units (channel wavelengths [nm], radii [um], angles
    [deg]), the normalization, the largest error estimate of each channel and
    radius, the inputs' hashes of every point, and the SHA-256 of the raw file.
``<stem>.glsl``
    ``vec3 <Name>Theta(sampler2DArray lut, float rEffUm, float thetaRad)``
    and ``vec3 <Name>(sampler2DArray lut, float rEffUm, float nu)`` (nu =
    cos theta): the phase function of the first three channels (R, G, B)
    interpolated linearly in radius between the two neighbouring radii of the
    table (radii need not be evenly spaced) and linearly in angle between
    neighbouring samples (index (n_angles - 1) theta / pi, as the seed
    shader's ``MiePhaseFunction``), from exact texel reads (``texelFetch``,
    no filtering), so the result does not depend on the sampler's settings.
    A radius outside the table's range is held at the nearest end, and nu is
    clamped to [-1, 1]: the sidecar and the snippet's comment say so.

Angles are the sweep's own (uniform from 0 to 180 deg inclusive), so the
texture holds the sweep's values rounded to float32 and nothing is
resampled.  Channels are wavelengths of the sweep's grid: none is
interpolated.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

import dustoptics._validation as _validation
from dustoptics.io._atomic import write_files
from dustoptics.io.shaders.glsl import glsl_float
from dustoptics.table import PHASE_NORMALIZATION

__all__ = ["LOOKUP_FORMAT", "lookup_glsl", "write_lookup"]

#: Format name and version written in every sidecar.
LOOKUP_FORMAT = "dustoptics-phase-lut3d/1"

#: Default channels R, G, B: the seed shader's wavelengths. [nm]
DEFAULT_CHANNELS_NM = (680.0, 550.0, 440.0)

_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def _read_coordinates(axis: str) -> tuple[str, ...]:
    return (axis, "theta_deg", "wavelength_nm")


def _lookup_arrays(
    ds: Any, axis: str, channels_nm: Sequence[float]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, Any]:
    """(phase (channels, radii, angles) float64, radii, theta, channels, the
    dataset reduced to the radius axis)."""
    if axis not in ds.dims:
        raise ValueError(
            f"axis {axis!r} is not a dimension of the sweep; its dimensions: {list(ds.dims)}"
        )
    others = [d for d in ds.phase.dims if d not in (axis, "wavelength_nm", "theta_deg")]
    wide = [d for d in others if ds.sizes[d] > 1]
    if wide:
        raise ValueError(
            f"the sweep has other axes with several values ({', '.join(f'{d}: {ds.sizes[d]}' for d in wide)}); "
            f"select one value of each first, e.g. ds.isel({{{wide[0]!r}: 0}})"
        )
    ds = ds.isel(dict.fromkeys(others, 0))
    # What is read below, from the declared sizes, before a value is read (a store opened
    # lazily may declare more than memory holds): float64, the phase function twice.
    declared = 8 * (2 * int(ds.phase.size) + sum(int(ds[k].size) for k in _read_coordinates(axis)))
    if declared > _validation.MEMORY_BUDGET_BYTES:
        raise ValueError(
            f"the sweep's phase function and coordinates read by write_lookup declare "
            f"{declared} bytes, beyond the memory budget of {_validation.MEMORY_BUDGET_BYTES} "
            "bytes (dustoptics._validation.MEMORY_BUDGET_BYTES); select fewer radii (ds.isel) "
            "first; refused before reading"
        )
    radii = np.asarray(ds[axis].values, dtype=np.float64)
    if radii.size < 2 or np.any(np.diff(radii) <= 0):
        raise ValueError(
            f"axis {axis!r} must hold at least 2 strictly increasing values; got {radii.tolist()}"
        )
    theta = np.asarray(ds.theta_deg.values, dtype=np.float64)
    uniform = np.linspace(0.0, 180.0, theta.size)
    if not np.allclose(theta, uniform, rtol=0.0, atol=1e-9):
        raise ValueError("the sweep's angles must be evenly spaced from 0 to 180 deg inclusive")
    wl = np.asarray(ds.wavelength_nm.values, dtype=np.float64)
    channels = np.asarray([float(c) for c in channels_nm], dtype=np.float64)
    if channels.size < 3:
        raise ValueError(
            f"channels_nm must hold at least 3 wavelengths (R, G, B); got {list(channels_nm)}"
        )
    index = []
    for c in channels:
        hit = np.flatnonzero(wl == c)
        if hit.size != 1:
            raise ValueError(
                f"channels_nm value {c:g} nm is not a wavelength of the sweep "
                f"(no interpolation in wavelength); its wavelengths: {wl.tolist()}"
            )
        index.append(int(hit[0]))
    phase = np.asarray(
        ds.phase.transpose(axis, "wavelength_nm", "theta_deg").values, dtype=np.float64
    )
    if not np.all(np.isfinite(phase)):
        raise ValueError(
            "the sweep's phase function holds non-finite values (an unfinished store?)"
        )
    return np.ascontiguousarray(phase[:, index, :].transpose(1, 0, 2)), radii, theta, channels, ds


def lookup_glsl(
    radii_um: np.ndarray, n_angles: int, *, name: str = "DustPhase", comment: str = ""
) -> str:
    """GLSL 3.30+ functions reading the lookup (see the module docstring).

    Parameters
    ----------
    radii_um : numpy.ndarray
        The radius axis, strictly increasing. [um]
    n_angles : int
        Angle samples over 0..180 deg inclusive. [-]
    name : str
        Function name (a GLSL identifier); constants are prefixed with it.
    comment : str
        Text for the header comment.
    """
    if not (
        isinstance(name, str)
        and _IDENTIFIER.match(name)
        and "__" not in name
        and not name.startswith("gl_")
    ):
        raise ValueError(f"name must be a GLSL identifier (no '__', not 'gl_...'); got {name!r}")
    n_r = int(radii_um.size)
    upper = name.upper()
    values = ", ".join(glsl_float(float(r)) for r in radii_um)
    lines = [
        f"// {name}: dust phase function [sr^-1] over effective radius and angle (dustoptics lookup).",
        *(f"// {line}" for line in comment.splitlines()),
        "// lut: sampler2DArray of width = angles, height = radii, layers = channels (R, G, B first).",
        "// Linear in radius between neighbours (radii outside the table are held at its ends) and",
        "// linear in angle between samples; nu = cos(theta) is clamped to [-1, 1].",
        f"const int {upper}_N_ANGLES = {int(n_angles)};",
        f"const int {upper}_N_RADII = {n_r};",
        f"const float {upper}_RADII_UM[{n_r}] = float[{n_r}]({values});",
        "",
        f"vec3 {name}Texel(sampler2DArray lut, int i, int r) {{",
        "    return vec3(texelFetch(lut, ivec3(i, r, 0), 0).r, texelFetch(lut, ivec3(i, r, 1), 0).r,",
        "                texelFetch(lut, ivec3(i, r, 2), 0).r);",
        "}",
        "",
        f"vec3 {name}Theta(sampler2DArray lut, float rEffUm, float thetaRad) {{",
        f"    float x = clamp(rEffUm, {upper}_RADII_UM[0], {upper}_RADII_UM[{n_r - 1}]);",
        "    int r = 0;",
        f"    for (int k = 1; k < {upper}_N_RADII - 1; ++k) {{",
        f"        if (x >= {upper}_RADII_UM[k]) r = k;",
        "    }",
        f"    float t = (x - {upper}_RADII_UM[r]) / ({upper}_RADII_UM[r + 1] - {upper}_RADII_UM[r]);",
        f"    float u = clamp(thetaRad, 0.0, 3.14159265358979) * (float({upper}_N_ANGLES - 1) / 3.14159265358979);",
        f"    int i = min(int(u), {upper}_N_ANGLES - 2);",
        "    float f = u - float(i);",
        f"    vec3 lo = mix({name}Texel(lut, i, r), {name}Texel(lut, i + 1, r), f);",
        f"    vec3 hi = mix({name}Texel(lut, i, r + 1), {name}Texel(lut, i + 1, r + 1), f);",
        "    return mix(lo, hi, t);",
        "}",
        "",
        f"vec3 {name}(sampler2DArray lut, float rEffUm, float nu) {{",
        f"    return {name}Theta(lut, rEffUm, acos(clamp(nu, -1.0, 1.0)));",
        "}",
        "",
    ]
    return "\n".join(lines)


def write_lookup(
    ds: Any,
    stem: str | os.PathLike[str],
    *,
    axis: str = "size_distribution.r_eff_um",
    channels_nm: Sequence[float] = DEFAULT_CHANNELS_NM,
    name: str = "DustPhase",
    overwrite: bool = False,
) -> list[Path]:
    """Write a sweep over a radius axis as a texture array, sidecar and GLSL.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep (:func:`dustoptics.sweep.sweep`) with dimension ``axis``;
        other axes must have one value (select it first).
    stem : str or os.PathLike
        Output path without suffix: ``<stem>.raw``, ``.json``, ``.glsl``.
    axis : str
        The radius axis, in um (default ``size_distribution.r_eff_um``).
    channels_nm : sequence of float
        Wavelengths of the channels, on the sweep's grid; the first three are
        R, G, B of the GLSL function. [nm]
    name : str
        GLSL function name.
    overwrite : bool
        Replace existing files.

    Returns
    -------
    list of pathlib.Path
        The three files (written atomically, all or none).
    """
    phase, radii, theta, channels, reduced = _lookup_arrays(ds, axis, channels_nm)
    raw = phase.astype("<f4").tobytes(order="C")
    stem = Path(stem)
    errors = None
    if "error_estimate" in reduced:
        wl = np.asarray(reduced.wavelength_nm.values)
        err = np.asarray(reduced.error_estimate.transpose(axis, "wavelength_nm").values)
        errors = [
            [float(err[i, int(np.flatnonzero(wl == c)[0])]) for i in range(radii.size)]
            for c in channels
        ]
    hashes = None
    if "provenance" in reduced:
        hashes = [
            json.loads(str(v))["input_hash"] for v in np.asarray(reduced.provenance.values).ravel()
        ]
    sidecar = {
        "format": LOOKUP_FORMAT,
        "file": stem.name + ".raw",
        "sha256": hashlib.sha256(raw).hexdigest(),
        "dtype": "<f4",
        "byte_order": "little",
        "order": "C",
        "shape": [int(channels.size), int(radii.size), int(theta.size)],
        "gl": {
            "target": "GL_TEXTURE_2D_ARRAY",
            "internal_format": "GL_R32F",
            "format": "GL_RED",
            "type": "GL_FLOAT",
            "width": int(theta.size),
            "height": int(radii.size),
            "layers": int(channels.size),
            "unpack_alignment": 4,
        },
        "axes": [
            {
                "name": "wavelength_nm",
                "units": "nm",
                "values": channels.tolist(),
                "role": "layer (channel)",
            },
            {"name": axis, "units": "um", "values": radii.tolist(), "role": "row (texel y)"},
            {
                "name": "theta_deg",
                "units": "degree",
                "values": theta.tolist(),
                "role": "column (texel x)",
            },
        ],
        "quantity": "phase function",
        "units": "sr-1",
        "normalization": PHASE_NORMALIZATION,
        "interpolation": (
            "linear in radius between neighbouring radii (held at the ends outside the range), "
            "linear in angle between samples; no interpolation in wavelength"
        ),
        "error_estimate": errors,
        "input_hashes": hashes,
        "sweep": reduced.attrs.get("sweep"),
        "accuracy": reduced.attrs.get("accuracy"),
    }
    comment = f"{int(channels.size)} channels at {', '.join(f'{c:g}' for c in channels)} nm; " + (
        f"radius axis {axis} [um]"
    )
    files = {
        stem.with_name(stem.name + ".raw"): raw,
        stem.with_name(stem.name + ".json"): (
            json.dumps(sidecar, indent=1, sort_keys=True) + "\n"
        ).encode(),
        stem.with_name(stem.name + ".glsl"): lookup_glsl(
            radii, theta.size, name=name, comment=comment
        ).encode(),
    }
    return write_files(files, overwrite=overwrite)
