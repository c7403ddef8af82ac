"""The LMD Mars PCM's infrared dust file (format ``lmd-dustir``).

``<name>_optprop_dustir_n<nsize>.dat``: Q_ext, single-scattering albedo and g per
wavelength and effective radius, over the PCM's infrared bands (5-200 um) with its
reference wavelength 9.3 um, in the layout of the PCM's ``optprop_dustir_n50.dat``
(:mod:`dustoptics.io.gcm.lmd`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from dustoptics.io.gcm.lmd import LmdOptions, describe_lmd, is_lmd, write_lmd
from dustoptics.io.registry import Format, register

__all__ = ["RECORD", "write_lmd_dustir"]


def write_lmd_dustir(
    table: Any, out_dir: str | os.PathLike[str], *, overwrite: bool = False, **keywords: Any
) -> list[Path]:
    """Write the infrared file (:func:`dustoptics.io.gcm.lmd.write_lmd`, ``domain="ir"``)."""
    return write_lmd(table, out_dir, domain="ir", overwrite=overwrite, **keywords)


RECORD = register(
    Format(
        name="lmd-dustir",
        summary="NAME_optprop_dustir_nN.dat: LMD Mars PCM infrared dust file (Q_ext, albedo, "
        "g per wavelength and radius)",
        write=write_lmd_dustir,
        suffixes=(".dat",),
        options=LmdOptions,
        recognise=lambda path: is_lmd(path) and "_optprop_dustir_" in path.name,
        describe=describe_lmd,
    )
)
