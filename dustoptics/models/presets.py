"""Named dust models: the package's preset configuration files.

Each preset is a TOML file in ``dustoptics/models/data/presets/`` that follows the
schema of :mod:`dustoptics.models.config`, with comments saying what it is, its
sources with full citations and every choice its sources left open.  Copy one
(:func:`preset_text`), edit it, and build it with
:func:`dustoptics.models.files.load_config` and :func:`dustoptics.models.compute.build_table`.

The folder is the registry: :func:`preset_registry` reads it once into one
:class:`Preset` record per file (name, file, one-line summary from the file's
``description``), and everything that lists presets (:func:`list_presets`, the
``presets`` command, the table below, checked by the tests) reads that.  Adding a
preset is adding a file.

========================  ======================================================
``blue-moons``            Blue Moon's dust (Meyran 2022 after Ehlers et al. 2014),
                          physical cross-section weighting, default grids
                          (the default preset)
``blue-moons-seed``       the seed thesis's published table as it made it:
                          number weighting, 1,800 angles
``hybrid``                ``blue-moons`` blended 50/50 with Costa et al.'s Mars
                          DHG, g1 clamped outside 440-680 nm
``hybrid-seed``           ``blue-moons-seed`` blended 50/50 with Costa's DHG,
                          Meyran's quadratic g1 as the seed used it
``costa``                 Costa et al. 2021's Mars DHG alone (phase only)
``collienne``             Collienne et al. 2013's Cornette-Shanks aerosol,
                          g = 0.8 (phase only)
``cosmoscout-mars``       CosmoScout VR's two-mode Mars aerosols, computed by
                          quadrature instead of random radii
``mer-sky-fit``           Wolff et al. 2009's Mars dust, r_eff fitted by
                          :mod:`dustoptics.retrieve` so that the rovers' view
                          of the sky is inside the MER colour range
========================  ======================================================

>>> from dustoptics.models import presets
>>> presets.list_presets()[:2]
['blue-moons', 'blue-moons-seed']
>>> presets.load_preset("blue-moons").optics.weighting
'scattering'
"""

from __future__ import annotations

import functools
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from types import MappingProxyType
from typing import Any, Final

from dustoptics.models.compute import build_table
from dustoptics.models.config import BuildConfig, parse_config
from dustoptics.table import Table

__all__ = [
    "DEFAULT_PRESET",
    "Preset",
    "build_preset",
    "list_presets",
    "load_preset",
    "preset_registry",
    "preset_text",
]

#: The preset built when none is named.
DEFAULT_PRESET: Final = "blue-moons"

_SUFFIX: Final = ".toml"


def _directory() -> Any:
    return resources.files("dustoptics.models").joinpath("data", "presets")


@dataclass(frozen=True)
class Preset:
    """One shipped preset, as the registry lists it.

    Attributes
    ----------
    name : str
        The preset's name (its file's name without ``.toml``, and its ``name`` key).
    file : str
        File name in ``dustoptics/models/data/presets/``.
    summary : str
        First line of the configuration's ``description``.
    default : bool
        Whether it is :data:`DEFAULT_PRESET`.
    """

    name: str
    file: str
    summary: str
    default: bool


@functools.cache
def preset_registry() -> Mapping[str, Preset]:
    """The shipped presets, by name, sorted: one record per file of the presets folder.

    Read once, as plain TOML (:func:`load_preset` validates a preset when it is used).

    Returns
    -------
    Mapping of str to Preset
    """
    names = sorted(
        entry.name[: -len(_SUFFIX)]
        for entry in _directory().iterdir()
        if entry.name.endswith(_SUFFIX) and entry.is_file()
    )
    records = {}
    for name in names:
        data = tomllib.loads(_directory().joinpath(name + _SUFFIX).read_text(encoding="utf-8"))
        description = data.get("description", "")
        records[name] = Preset(
            name=name,
            file=name + _SUFFIX,
            summary=(description.splitlines() or [""])[0] if isinstance(description, str) else "",
            default=name == DEFAULT_PRESET,
        )
    return MappingProxyType(records)


def list_presets() -> list[str]:
    """Names of the shipped presets, sorted.

    Returns
    -------
    list of str
    """
    return list(preset_registry())


def _check_name(name: Any) -> str:
    names = list_presets()
    if not isinstance(name, str) or name not in names:
        raise ValueError(f"unknown preset {name!r}; valid presets: {', '.join(names)}")
    return name


def preset_text(name: str) -> str:
    """The TOML text of a preset, to read or to copy and edit.

    Parameters
    ----------
    name : str
        A name of :func:`list_presets`.

    Returns
    -------
    str

    Raises
    ------
    ValueError
        Unknown name (the message lists the valid ones).
    """
    return _directory().joinpath(_check_name(name) + _SUFFIX).read_text(encoding="utf-8")


def load_preset(name: str) -> BuildConfig:
    """A preset's validated configuration.

    Raises
    ------
    ValueError
        Unknown name (the message lists the valid ones).
    """
    return _load(_check_name(name))


def _load(name: str) -> BuildConfig:
    """The configuration of the preset file ``name`` (a name of the folder)."""
    text = _directory().joinpath(name + _SUFFIX).read_text(encoding="utf-8")
    config = parse_config(text, source=f"preset {name}{_SUFFIX}")
    if config.name != name:  # a packaging mistake, not a user error
        raise RuntimeError(f"preset file {name}{_SUFFIX} declares name = {config.name!r}")
    return config


def build_preset(name: str = DEFAULT_PRESET, **kwargs: Any) -> Table:
    """Compute a preset's table.

    Parameters
    ----------
    name : str, optional
        A name of :func:`list_presets`; default :data:`DEFAULT_PRESET`.
    **kwargs
        ``workers`` and ``progress`` of :func:`dustoptics.models.compute.build_table`.

    Returns
    -------
    Table

    Raises
    ------
    ValueError
        Unknown name (the message lists the valid ones).
    """
    return build_table(load_preset(name), **kwargs)
