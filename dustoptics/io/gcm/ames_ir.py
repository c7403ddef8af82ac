"""The NASA Ames Mars GCM's infrared dust file (format ``ames-dustir``).

``<name>_Dust_ir_15bands.dat`` (and its ``.json`` sidecar): per radius, Q_ext, Q_sca and
g averaged over each of the model's 8 infrared bands (4.5-1000 um), Planck-weighted at
215 K, in the layout of its ``Dust_ir_wolff2010_JD_15bands.dat``
(:mod:`dustoptics.io.gcm.ames`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from dustoptics.io.gcm.ames import AmesOptions, describe_ames, is_ames, write_ames
from dustoptics.io.registry import Format, register

__all__ = ["RECORD", "write_ames_dustir"]


def write_ames_dustir(
    table: Any, out_dir: str | os.PathLike[str], *, overwrite: bool = False, **keywords: Any
) -> list[Path]:
    """Write the infrared file (:func:`dustoptics.io.gcm.ames.write_ames`, ``bands="ir"``)."""
    return write_ames(table, out_dir, bands="ir", overwrite=overwrite, **keywords)


RECORD = register(
    Format(
        name="ames-dustir",
        summary="NAME_Dust_ir_15bands.dat: NASA Ames Mars GCM infrared dust file (Q_ext, "
        "Q_sca, g per band and radius) and a JSON sidecar",
        write=write_ames_dustir,
        suffixes=(".dat", ".json"),
        options=AmesOptions,
        recognise=lambda path: is_ames(path, "ir"),
        describe=describe_ames,
    )
)
