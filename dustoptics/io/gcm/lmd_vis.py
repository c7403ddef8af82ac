"""The LMD Mars PCM's visible dust file (format ``lmd-dustvis``).

``<name>_optprop_dustvis_n<nsize>.dat``: Q_ext, single-scattering albedo and g per
wavelength and effective radius, over the PCM's visible bands (0.1-5 um) with its
reference wavelength 0.67 um, in the layout of the PCM's ``optprop_dustvis_TM_n50.dat``
(:mod:`dustoptics.io.gcm.lmd`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from dustoptics.io.gcm.lmd import LmdOptions, describe_lmd, is_lmd, write_lmd
from dustoptics.io.registry import Format, register

__all__ = ["RECORD", "write_lmd_dustvis"]


def write_lmd_dustvis(
    table: Any, out_dir: str | os.PathLike[str], *, overwrite: bool = False, **keywords: Any
) -> list[Path]:
    """Write the visible file (:func:`dustoptics.io.gcm.lmd.write_lmd`, ``domain="vis"``)."""
    return write_lmd(table, out_dir, domain="vis", overwrite=overwrite, **keywords)


RECORD = register(
    Format(
        name="lmd-dustvis",
        summary="NAME_optprop_dustvis_nN.dat: LMD Mars PCM visible dust file (Q_ext, albedo, "
        "g per wavelength and radius)",
        write=write_lmd_dustvis,
        suffixes=(".dat",),
        options=LmdOptions,
        recognise=lambda path: is_lmd(path) and "_optprop_dustvis_" in path.name,
        describe=describe_lmd,
    )
)
