"""The NASA Ames Mars GCM's visible dust file (format ``ames-dustvis``).

``<name>_Dust_vis_15bands.dat`` (and its ``.json`` sidecar): per radius, Q_ext, Q_sca and
g averaged over each of the model's 7 visible bands (0.24-4.5 um), Planck-weighted at
6000 K, in the layout of its ``Dust_vis_wolff2010_JD_15bands.dat``
(:mod:`dustoptics.io.gcm.ames`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from dustoptics.io.gcm.ames import AmesOptions, describe_ames, is_ames, write_ames
from dustoptics.io.registry import Format, register

__all__ = ["RECORD", "write_ames_dustvis"]


def write_ames_dustvis(
    table: Any, out_dir: str | os.PathLike[str], *, overwrite: bool = False, **keywords: Any
) -> list[Path]:
    """Write the visible file (:func:`dustoptics.io.gcm.ames.write_ames`, ``bands="vis"``)."""
    return write_ames(table, out_dir, bands="vis", overwrite=overwrite, **keywords)


RECORD = register(
    Format(
        name="ames-dustvis",
        summary="NAME_Dust_vis_15bands.dat: NASA Ames Mars GCM visible dust file (Q_ext, "
        "Q_sca, g per band and radius) and a JSON sidecar",
        write=write_ames_dustvis,
        suffixes=(".dat", ".json"),
        options=AmesOptions,
        recognise=lambda path: is_ames(path, "vis"),
        describe=describe_ames,
    )
)
