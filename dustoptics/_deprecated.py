"""Old import paths that keep working for one release after a module moved.

A module that moved leaves a two-line shim at its old path::

    from dustoptics._deprecated import alias_module
    alias_module(__name__, "dustoptics.io.tables.netcdf")

Importing the old path then warns (:class:`DeprecationWarning`, pointing at the importing
line) and gives the new module itself, so ``isinstance`` checks and monkeypatching see one
object.  A name that moved out of a module that stays is served by that module's
``__getattr__`` (:func:`moved_attribute`) in the same way.  The package's own code and tests
never import a shim or a moved name by its old path.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from collections.abc import Mapping
from typing import Any

#: The release in which the old paths are removed.
REMOVED_IN = "0.3"


def _importer_stacklevel(old_name: str) -> int:
    """The ``stacklevel`` (seen from :func:`alias_module`) of the line that imported the shim."""
    frame = sys._getframe(2)  # the shim module's own frame
    level = 1
    # warnings.warn skips importlib's own frames when it counts (CPython's _is_internal_frame).
    while frame is not None and (
        frame.f_code.co_filename.startswith("<frozen importlib")
        or frame.f_globals.get("__name__") == old_name
    ):
        if frame.f_globals.get("__name__") == old_name:
            level += 1
        frame = frame.f_back  # type: ignore[assignment]
    return level + 1  # the importer


def alias_module(old_name: str, new_name: str) -> None:
    """Make the module ``old_name`` an alias of ``new_name``, with a DeprecationWarning.

    Parameters
    ----------
    old_name : str
        The old, dotted module path (the shim's ``__name__``).
    new_name : str
        The dotted path the module moved to.
    """
    warnings.warn(
        f"{old_name} moved to {new_name}; the old path is removed in {REMOVED_IN}",
        DeprecationWarning,
        stacklevel=_importer_stacklevel(old_name),
    )
    module = importlib.import_module(new_name)
    sys.modules[old_name] = module
    parent, _, child = old_name.rpartition(".")
    if parent in sys.modules:
        setattr(sys.modules[parent], child, module)


def moved_attribute(old_module: str, name: str, moved: Mapping[str, str]) -> Any:
    """A name that moved to another module, for the old module's ``__getattr__``.

    A module some of whose names moved keeps them importable for one release::

        _MOVED = {"MultiModal": "dustoptics.particles.custom_sizedist"}

        def __getattr__(name: str) -> Any:
            return moved_attribute(__name__, name, _MOVED)

    ``old_module.name`` then warns (:class:`DeprecationWarning`, pointing at the line that
    asked for it) and gives the object itself.  The new module is looked up by its name when
    the old name is used, so the old module does not import it.

    Parameters
    ----------
    old_module : str
        The dotted path of the module the names moved from (its ``__name__``).
    name : str
        The name asked for.
    moved : Mapping of str to str
        Each moved name and the dotted path of the module it moved to.

    Raises
    ------
    AttributeError
        If ``name`` is not one of ``moved`` (as for any missing module attribute).
    """
    if name not in moved:
        raise AttributeError(f"module {old_module!r} has no attribute {name!r}")
    new_module = moved[name]
    warnings.warn(
        f"{old_module}.{name} moved to {new_module}.{name}; the old path is removed in "
        f"{REMOVED_IN}",
        DeprecationWarning,
        stacklevel=3,  # the caller of the old module's __getattr__
    )
    return getattr(importlib.import_module(new_module), name)
