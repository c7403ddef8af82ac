"""Configuration files users write: reading them, checked against the presets.

A user copies a preset (``dustoptics presets --show NAME > my.toml``,
:func:`dustoptics.models.presets.preset_text`), edits it and reads it back with
:func:`load_config`.  The file is validated as :func:`dustoptics.models.config.parse_config`
validates any text; what this module adds is the check that an edited copy does not keep
the preset's name, sources or choices, which would label the table with a model it is
not (:func:`preset_copy_problems`, :class:`PresetCopyWarning`).  It builds on both
:mod:`dustoptics.models.config` and :mod:`dustoptics.models.presets`, so neither of them
needs the other's help to read a file.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Final

from dustoptics._files import read_config_text
from dustoptics.models import presets
from dustoptics.models.config import BuildConfig, parse_config

__all__ = ["PresetCopyWarning", "load_config", "preset_copy_problems"]


class PresetCopyWarning(UserWarning):
    """A configuration file labels its table with a preset's name, sources or choices
    although its parameters differ from that preset's."""


#: The sections of a configuration that determine its numbers (see BuildConfig.to_inputs).
_COMPUTATIONAL_KEYS: Final = (
    "material",
    "size_distribution",
    "optics",
    "phase",
    "number_density_per_m3",
)


def preset_copy_problems(config: BuildConfig) -> list[str]:
    """How ``config`` still carries the labels of a preset whose parameters it changed.

    ``dustoptics presets --show NAME > my.toml`` gives a copy to edit.  Once
    its parameters are edited, the preset's ``name``, ``sources`` and
    ``choices`` describe another model: kept, they would label the table with
    citations and choices that are not its own.  A configuration counts as a
    copy of a preset when it has the preset's name, or both its sources and its
    choices (presets may share publications).  Empty when ``config`` is a
    preset itself, an unchanged copy of one, or has labels of its own.

    Examples
    --------
    >>> from dataclasses import replace
    >>> preset = presets.load_preset("blue-moons")
    >>> preset_copy_problems(preset)
    []
    >>> edited = replace(preset, number_density_per_m3=1e8)
    >>> print(preset_copy_problems(edited)[0])  # doctest: +ELLIPSIS
    carries the name, sources and choices of preset 'blue-moons' but its number_density_per_m3 differ...
    """
    inputs = config.to_inputs()
    inputs["optics"].pop("expansion", None)  # more coefficients of the same model, not another
    problems = []
    for name in presets.list_presets():
        preset = presets.load_preset(name)
        labels = [
            label
            for label, same in (
                ("name", config.name == preset.name),
                ("sources", bool(preset.sources) and config.sources == preset.sources),
                ("choices", bool(preset.choices) and config.choices == preset.choices),
            )
            if same
        ]
        # Presets may share their publications (hybrid, hybrid-seed): a copy is one that
        # kept the preset's name, or both its sources and its choices.
        if "name" not in labels and len(labels) < 2:
            continue
        theirs = preset.to_inputs()
        changed = [key for key in _COMPUTATIONAL_KEYS if inputs.get(key) != theirs.get(key)]
        if not changed:
            continue
        carried = labels[0] if len(labels) == 1 else ", ".join(labels[:-1]) + " and " + labels[-1]
        problems.append(
            f"carries the {carried} of preset {name!r} but its {', '.join(changed)} differ "
            "from the preset's: the table would be labelled with a model it is not. Give "
            "the configuration its own name, and sources and choices that describe it"
        )
    return problems


def load_config(path: str | os.PathLike[str]) -> BuildConfig:
    """Read and validate a TOML build configuration file (UTF-8).

    A file that still carries the name, sources or choices of a preset whose
    parameters it changed (an edited copy of ``dustoptics presets --show``)
    gives a :class:`PresetCopyWarning` (:func:`preset_copy_problems`).

    Raises
    ------
    dustoptics.models.config.ConfigError
        As :func:`~dustoptics.models.config.parse_config`, with the path in the message.
    dustoptics.io.FormatError
        Not a regular file (a FIFO, a device), larger than
        :data:`dustoptics._files.MAX_CONFIG_BYTES`, or not UTF-8 text: refused before it is read.
    OSError
        If the file cannot be read.
    """
    p = Path(path)
    config = parse_config(read_config_text(p), source=str(p))
    for problem in preset_copy_problems(config):
        warnings.warn(f"configuration {str(p)!r} {problem}", PresetCopyWarning, stacklevel=2)
    return config
