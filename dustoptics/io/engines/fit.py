"""Fitted analytic phase-function parameters as JSON and as shader constants.

:func:`fit_json` gives the parameters of a
:class:`~dustoptics.scattering.fit.FitResult` with their errors as JSON;
:func:`fit_constants` gives them as constant declarations in GLSL, HLSL or
WGSL (:data:`FIT_LANGUAGES`), small literal snippets to paste beside an
engine's own analytic phase function:

- three rows (colour channels): one three-component vector per parameter
  (``vec3``, ``float3``, ``vec3<f32>``), components in R, G, B order;
- any other number of rows (per wavelength): one float array per parameter
  and one of the wavelengths.

Each value is rounded to float32 and written as the shortest decimal that
reads back as that float32.  GLSL arrays need GLSL 1.20 or GLSL ES 3.00;
vectors compile in any version.  :func:`write_fit` writes the four files at
once (all or none).
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import numpy as np

from dustoptics._validation import check_choice
from dustoptics.io._atomic import safe_stem, write_files
from dustoptics.io.shaders.common import shader_syntax
from dustoptics.scattering.fit import FitResult

__all__ = ["FIT_LANGUAGES", "fit_constants", "fit_json", "write_fit"]

#: Shading languages :func:`fit_constants` writes.
FIT_LANGUAGES = ("glsl", "hlsl", "wgsl")

_IDENTIFIER = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def fit_json(result: FitResult) -> str:
    """The fit as indented JSON text (model, loss, per-row parameters and errors)."""
    return json.dumps(result.to_dict(), indent=2, allow_nan=False) + "\n"


def fit_constants(result: FitResult, *, language: str, prefix: str = "DUST") -> str:
    """Constant declarations of the fitted parameters in a shading language.

    Parameters
    ----------
    result : FitResult
        The fit.
    language : {"glsl", "hlsl", "wgsl"}
        The shading language.
    prefix : str
        Start of every declared name: ``<PREFIX>_<PARAMETER>`` (upper case),
        e.g. ``DUST_G1``; a letter, then letters, digits or ``_``, no ``__``.

    Returns
    -------
    str
        ASCII source: a comment header (model, formula, normalization, loss,
        errors per row) and one declaration per parameter, plus the
        wavelengths [nm], the largest relative error and the error in g.

    Examples
    --------
    >>> from dustoptics.scattering.fit import fit_phase
    >>> from dustoptics.scattering.phase import henyey_greenstein
    >>> theta = np.linspace(0.0, 180.0, 181)
    >>> p = henyey_greenstein(np.cos(np.deg2rad(theta)), g=[[0.7], [0.6], [0.5]])
    >>> r = fit_phase(theta, p, model="hg", labels=["R", "G", "B"])
    >>> print(fit_constants(r, language="wgsl").splitlines()[-3])
    const DUST_G: vec3<f32> = vec3<f32>(7.0e-01f, 6.0e-01f, 5.0e-01f);
    """
    check_choice("language", language, FIT_LANGUAGES)
    if not isinstance(prefix, str) or not _IDENTIFIER.match(prefix) or "__" in prefix:
        raise ValueError(
            "prefix must start with a letter and hold only letters, digits and '_' (no '__'); "
            f"got {prefix!r}"
        )
    rows = result.parameters.shape[0]
    channels = rows == 3
    comment = "//"
    lines = [
        f"{comment} dustoptics fit: {result.model} ({result.formula})",
        f"{comment} source: {result.citation}",
        f"{comment} normalization: 2 pi int P dmu = 1 (per steradian), mu = cos(theta), theta = 0 "
        "forward",
        f"{comment} loss: {result.loss}",
        f"{comment} rows ({'vector components' if channels else 'array entries'}): "
        + ", ".join(result.labels),
    ]
    for i, label in enumerate(result.labels):
        lines.append(
            f"{comment}   {label}: max |M/T - 1| = {result.max_relative_error[i]:.3g}, median "
            f"{result.median_relative_error[i]:.3g}, g error {result.g_error[i]:+.3g}"
        )
    if language == "glsl" and not channels:
        lines.append(f"{comment} arrays need GLSL 1.20 or GLSL ES 3.00")
    lines.append("")
    columns = [
        (name.upper(), result.parameters[:, k]) for k, name in enumerate(result.parameter_names)
    ]
    columns += [
        ("WAVELENGTH_NM", np.asarray(result.wavelength_nm)),
        ("FIT_MAX_REL_ERROR", np.asarray(result.max_relative_error)),
        ("FIT_G_ERROR", np.asarray(result.g_error)),
    ]
    sx = shader_syntax(language)
    for name, values in columns:
        if not np.all(np.isfinite(values)):
            continue  # e.g. rows fitted without a wavelength
        full_name, values = f"{prefix}_{name}", np.asarray(values, dtype=np.float64)
        if channels:
            lines.append(sx.const("vec3", full_name, sx.vec(values), ""))
        else:
            lines.append(sx.float_array(full_name, values))
    return "\n".join(lines) + "\n"


def write_fit(
    result: FitResult,
    out_dir: str | os.PathLike[str],
    *,
    stem: str,
    prefix: str = "DUST",
    overwrite: bool = False,
) -> list[Path]:
    """Write ``<stem>_<model>.json`` and the GLSL, HLSL and WGSL constants, all or none.

    Parameters
    ----------
    result : FitResult
    out_dir : path
        Directory (created if missing).
    stem : str
        File-name stem, e.g. the table's name.
    prefix : str
        Name prefix of the shader constants.
    overwrite : bool
        Replace existing files.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    base = Path(out_dir)
    name = f"{safe_stem(stem)}_{result.model}"
    files: dict[Path, bytes] = {base / f"{name}.json": fit_json(result).encode("utf-8")}
    for language in FIT_LANGUAGES:
        source = fit_constants(result, language=language, prefix=prefix)
        path = base / f"{name}{shader_syntax(language).extension}"
        files[path] = source.encode("ascii", "replace")
    return write_files(files, overwrite=overwrite)
