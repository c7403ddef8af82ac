"""Packages whose public names are imported on first use (PEP 562).

A package ``__init__`` that imported every module of the package made importing one
of them import them all: ``dustoptics build`` imported every format's writer (and
with them scipy.integrate, the atmosphere sets, the engines) to write a netCDF file.
A package built with :func:`lazy_attribute` names what it offers and imports it when
it is first used: ``from dustoptics.io import FORMATS`` imports the registry only.

``__all__`` stays a literal list beside the name map (type checkers read it: a name of a
typed package is re-exported when ``__all__`` lists it); the tests check that they agree.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Iterable, Mapping
from typing import Any

__all__ = ["lazy_attribute", "lazy_dir", "lazy_package"]


def lazy_attribute(
    package: str, name: str, names: Mapping[str, Iterable[str]], submodules: Iterable[str] = ()
) -> Any:
    """The public ``name`` of ``package``, imported now (a package's ``__getattr__``).

    Parameters
    ----------
    package : str
        The package (its ``__name__``).
    name : str
        The attribute asked for.
    names : mapping
        Defining module (absolute name) -> the public names it gives the package.
    submodules : iterable of str
        The package's submodules that are public names (``"csv"`` for ``package.csv``).

    Returns
    -------
    object
        The value, also set on the package (the next use does not come here).

    Raises
    ------
    AttributeError
        ``name`` is none of them.
    """
    if name in submodules:
        value = importlib.import_module(f"{package}.{name}")
    else:
        module = next((m for m, given in names.items() if name in given), None)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
    setattr(sys.modules[package], name, value)
    return value


def lazy_dir(package: str, public: Iterable[str]) -> list[str]:
    """The names of ``package``: those set on it and the ``public`` ones (its ``__dir__``)."""
    return sorted({*vars(sys.modules[package]), *public})


def lazy_package(
    package: str, names: Mapping[str, Iterable[str]], public: Iterable[str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """A package's ``__getattr__`` and ``__dir__``, for::

        __getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)

    ``names`` as for :func:`lazy_attribute`; the ``public`` names (``__all__``) that no
    module of ``names`` gives are the package's submodules (a name the package defines
    itself never reaches ``__getattr__``).
    """
    public = tuple(public)
    given = {n for module_names in names.values() for n in module_names}
    submodules = tuple(n for n in public if n not in given)

    def attribute(name: str) -> Any:
        """A public name, imported on first use."""
        return lazy_attribute(package, name, names, submodules)

    def listing() -> list[str]:
        return lazy_dir(package, public)

    return attribute, listing
