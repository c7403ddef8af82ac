"""The parameters ``compute_optics(derivatives=...)`` takes: their names, units,
and how a refractive index's parameters move m (``table_derivatives`` uses
them; split from it to keep that module to its sums)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from dustoptics.particles.sizedist import SizeDistribution
from dustoptics.particles.sizedist_derivatives import parameter_names

__all__ = [
    "INDEX_PARAMETERS",
    "check_parameters",
    "index_directions",
    "index_parameter_names",
    "parameter_unit",
]

#: Parameters of the refractive index itself: m = n + i k at every wavelength.
INDEX_PARAMETERS = ("n", "k")


def parameter_unit(name: str) -> str:
    """udunits2 unit of a parameter: ``"um"`` for names ending in ``_um``, else ``"1"``."""
    return "um" if name.endswith(("_um", "_um]")) else "1"


def index_parameter_names(refractive_index: Any) -> tuple[str, ...]:
    """Parameters of a refractive index besides ``"n"`` and ``"k"``: those of an
    object with ``index_parameters`` and ``index_derivatives`` (a
    :class:`~dustoptics.particles.mixing.Mixture`: its volume fraction and host index)."""
    names = getattr(refractive_index, "index_parameters", None)
    if names is None or not callable(getattr(refractive_index, "index_derivatives", None)):
        return ()
    return tuple(names)


def index_directions(
    refractive_index: Any, parameters: Sequence[str], wavelength_nm: np.ndarray
) -> dict[str, np.ndarray]:
    """dm/dp per wavelength for every parameter of the refractive index among
    ``parameters``: 1 for ``"n"``, 1j for ``"k"``, the index's own
    ``index_derivatives`` for the others (a mixture's, by the chain rule). [-]"""
    out: dict[str, np.ndarray] = {}
    own = [p for p in parameters if p in index_parameter_names(refractive_index)]
    if own:
        found = refractive_index.index_derivatives(wavelength_nm)
        for p in own:
            out[p] = np.asarray(found[p], dtype=np.complex128) * np.ones(wavelength_nm.size)
    for p, dm in (("n", 1.0 + 0j), ("k", 1j)):
        if p in parameters:
            out[p] = np.full(wavelength_nm.size, dm, dtype=np.complex128)
    return out


def check_parameters(
    derivatives: Any,
    distribution: SizeDistribution,
    extra: Sequence[str] = (),
) -> tuple[str, ...]:
    """The parameter names of ``compute_optics(derivatives=...)``, checked before any work.

    Parameters
    ----------
    derivatives : sequence of str
        Names: the distribution's (:func:`parameter_names`, or ``"radius_um"``
        of a monodisperse one), ``"n"``, ``"k"``, and ``extra`` (the
        refractive index's own, e.g. a mixture's ``"hematite_fraction"``).
    distribution : SizeDistribution
    extra : sequence of str
        Further allowed names.

    Returns
    -------
    tuple of str

    Raises
    ------
    TypeError
        ``derivatives`` is a string or not a sequence of strings.
    ValueError
        An unknown or repeated name; the message lists the allowed ones.
    """
    if isinstance(derivatives, str) or not isinstance(derivatives, Sequence):
        raise TypeError(
            "derivatives must be a sequence of parameter names, e.g. ('r_eff_um', 'n'); "
            f"got {derivatives!r}"
        )
    names = tuple(derivatives)
    if not names:
        return names
    if distribution.is_monodisperse:
        own: tuple[str, ...] = ("radius_um",)
    else:
        try:
            own = parameter_names(distribution)
        except (TypeError, ValueError):
            own = ()
    allowed = (*own, *INDEX_PARAMETERS, *extra)
    for p in names:
        if not isinstance(p, str) or p not in allowed:
            raise ValueError(
                f"derivatives: unknown parameter {p!r}; allowed for this distribution and "
                f"refractive index: {', '.join(map(repr, allowed))}"
            )
    if len(set(names)) != len(names):
        raise ValueError(f"derivatives must not repeat a parameter; got {names!r}")
    return names
