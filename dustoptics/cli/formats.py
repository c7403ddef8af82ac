"""The output formats on the command line: ``--format`` and the options of each format.

:func:`add_format_options` adds ``--format`` (:func:`parse_formats`), with one
line per format of :data:`dustoptics.io.FORMATS` in ``--help``
(:func:`format_lines`, generated from the registry), ``--force``,
``--allow-large`` and each format's options to ``build`` and ``export``.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Sequence

from dustoptics.cli.parser import _float_list, _positive_float, _positive_int

__all__ = ["add_format_options", "format_lines", "parse_formats"]

#: One line per format for ``--help``, by name; a format registered without one here is
#: described by the first sentence of its writer's docstring (:func:`format_lines`).
_FORMAT_HELP = {
    "bruneton": "Bruneton's (2017) aerosol: NAME_bruneton_mie.json, .glsl (needs N0)",
    "cosmoscout": "CosmoScout VR's NAME_phase.csv, _scattering, ... (needs N0)",
    "csv": "the seed's Mie*Spectrum.csv files and table_summary.json",
    "disort": "NAME_disort.txt: DISORT's moments (needs [optics] expansion)",
    "exr": "NAME_phase_*.exr: the phase texture as OpenEXR",
    "glsl": "NAME_phase.glsl: MiePhaseFunction(nu), GLSL 1.30+ or ES 1.00",
    "hdf5": "NAME.h5: the same file as netcdf, named .h5",
    "hlsl": "NAME_phase.hlsl: the same lookup in HLSL",
    "ktx2": "NAME_phase_*.ktx2: the phase texture as KTX2",
    "libradtran": "NAME_aerosol_*.dat: libRadtran's (needs [optics] expansion, N0)",
    "libradtran-nc": "NAME.mie.cdf: libRadtran's P11, P12, P33, P34 (needs [optics] expansion, N0)",
    "netcdf": "NAME.nc: the table and its provenance, CF netCDF-4",
    "npy": "NAME_phase_*.npy: the phase texture as NumPy .npy, JSON sidecar",
    "texture": "NAME_phase_theta.raw: float32 texture, JSON sidecar",
    "wgsl": "NAME_phase.wgsl: the same lookup in WGSL (WebGPU)",
}


def _writer_summary(writer: object) -> str:
    """The first sentence of a writer's docstring, without reST markup."""
    doc = (getattr(writer, "__doc__", None) or "").strip().split("\n\n")[0]
    text = " ".join(doc.split())
    text = re.sub(r":[a-z:]+:`~?([^`<]*?)(?: <[^>]*>)?`", lambda m: m[1].rsplit(".", 1)[-1], text)
    text = text.replace("``", "")
    return text.split(". ")[0].rstrip(".") or "(no description)"


def format_lines(default: Sequence[str] = ()) -> str:
    """One line per format of :data:`dustoptics.io.FORMATS`, for ``--help``.

    Parameters
    ----------
    default : sequence of str, optional
        The formats written when ``--format`` is not given, marked ``(default)``.

    Returns
    -------
    str
        ``"NAME  description"`` lines, names sorted.
    """
    from dustoptics.io import FORMATS

    width = max(map(len, FORMATS))
    lines = []
    for name in sorted(FORMATS):
        text = _FORMAT_HELP.get(name) or _writer_summary(FORMATS[name])
        mark = " (default)" if name in default else ""
        lines.append(f"{name:<{width}}  {text}{mark}")
    return "\n".join(lines)


def parse_formats(text: str) -> tuple[str, ...]:
    """``--format``: comma-separated names of :data:`dustoptics.io.FORMATS`, each once."""
    from dustoptics.io import FORMATS

    names = tuple(part.strip() for part in text.split(",") if part.strip())
    unknown = [n for n in names if n not in FORMATS]
    if not names or unknown:
        raise argparse.ArgumentTypeError(
            f"unknown format {', '.join(map(repr, unknown)) or repr(text)}; "
            f"choose from {', '.join(sorted(FORMATS))} (comma-separated)"
        )
    return tuple(dict.fromkeys(names))


def add_format_options(
    p: argparse.ArgumentParser, *, default: Sequence[str], required: bool
) -> None:
    g = p.add_argument_group(
        "formats (--format FMT[,FMT...], from dustoptics.io.FORMATS)", format_lines(default)
    )
    help_default = f" (default {','.join(default)})" if default else ""
    g.add_argument(
        "--format",
        type=parse_formats,
        default=None,
        required=required,
        metavar="FMT[,FMT...]",
        help=f"output formats, comma-separated: one or more of the formats listed here{help_default}",
    )
    p.add_argument("--force", action="store_true", help="replace existing output files")
    p.add_argument(
        "--allow-large",
        action="store_true",
        help="go ahead beyond the memory (2 GiB) and work (about ten minutes) budget",
    )
    g = p.add_argument_group("glsl, hlsl, wgsl")
    g.add_argument(
        "--channels-nm",
        type=_float_list,
        metavar="R,G,B",
        help="wavelengths of the three channels [nm] (default 680,550,440)",
    )
    g.add_argument(
        "--colour",
        choices=["cie1931-xyz", "linear-srgb-astmg173"],
        help="colour channels instead of three wavelengths: CIE 1931 XYZ bands, or linear sRGB of the "
        "table lit by the ASTM G173 sun (a renderer with a white sun reproduces the spectral colour)",
    )
    g.add_argument(
        "--resolution-deg",
        type=_positive_float,
        metavar="DEG",
        help="angular step of the constant array [deg] (default 0.25)",
    )
    g.add_argument(
        "--prefix",
        metavar="NAME",
        help="prefix of every identifier: NAME_PHASE, ..., NAME_MiePhaseFunction (default MIE, "
        "with the seed's MiePhaseFunction)",
    )
    g.add_argument(
        "--glsl-version",
        choices=["130", "100"],
        help="glsl: 130 = GLSL 1.30+ and ES 3.00+ (default); 100 = GLSL ES 1.00 (WebGL 1)",
    )
    g = p.add_argument_group("texture, ktx2, exr, npy (channels: --channels-nm, --colour)")
    g.add_argument(
        "--sampling",
        choices=["theta", "cos"],
        help="uniform in angle or in cos(angle) (default theta)",
    )
    g.add_argument(
        "--n-angles",
        type=_positive_int,
        metavar="N",
        help="samples along the angle axis (default 721)",
    )
    g.add_argument(
        "--layout",
        choices=["rgb", "wavelength"],
        help="ktx2, exr, npy: angle x RGB (default) or angle x wavelength",
    )
    g.add_argument(
        "--precision",
        choices=["float32", "float16"],
        help="ktx2, exr, npy: sample type (default float32)",
    )
    g = p.add_argument_group("cosmoscout (beta in m^-1 needs a number density)")
    g.add_argument(
        "--number-density-per-m3",
        type=_positive_float,
        metavar="N0",
        help="number density at the surface [m^-3] (overrides the configuration's; recorded "
        "in the table's provenance)",
    )
    g.add_argument(
        "--scale-height-m",
        type=_positive_float,
        default=10_000.0,
        metavar="H",
        help="exponential density profile's scale height [m] (default 10000, the seeds' Mars dust)",
    )
    g.add_argument(
        "--top-altitude-m",
        type=_positive_float,
        default=120_000.0,
        metavar="Z",
        help="atmosphere top above the surface [m] (default 120000, Mars 3510 - 3390 km)",
    )
    g.add_argument(
        "--n-altitudes",
        type=_positive_int,
        default=1024,
        metavar="N",
        help="density samples (default 1024)",
    )
