"""Compare two optical tables wavelength by wavelength.

:func:`compare_tables` shows what a modelling choice changes: the ratio of the
forward peaks, the asymmetry parameters, and the median and largest relative
difference of the phase functions over angle.  Its first use is the seed's
number weighting against the physical cross-section weighting::

    from dustoptics.models import presets
    from dustoptics.compare import compare_tables

    seed = presets.build_preset("blue-moons-seed")     # 1,800 angles
    physical = presets.build_preset("blue-moons")      # 1,801 angles
    print(compare_tables(seed, physical, theta_deg=range(181)))

At 360 nm the physical forward peak is 67.3 sr^-1 against the seed's
28.6 sr^-1, a ratio of 2.35.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from dustoptics._validation import _show
from dustoptics.table import Table

__all__ = [
    "ESTIMATE_RTOL",
    "SAME_TABLE_RTOL",
    "TableComparison",
    "compare_tables",
    "table_differences",
]

#: Relative tolerance under which two tables of the same inputs are the same
#: table: far below the tables' 1e-4 accuracy, far above the last-bit
#: differences a different CPU or library build may give. [-]
SAME_TABLE_RTOL = 1e-9
#: The error estimates are differences of nearly equal quadrature sums, so
#: round-off moves them ~1000x more (measured: 1.7e-9 from a change in how one
#: complex division rounds); they are compared to this looser tolerance. [-]
ESTIMATE_RTOL = 1e-6

_SAME_TABLE_ARRAYS = (
    "phase",
    "g",
    "cext_um2",
    "csca_um2",
    "error_estimate",
    "cross_section_error_estimate",
)


def _readonly(values: Any) -> np.ndarray:
    arr = np.array(values, dtype=np.float64)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class TableComparison:
    """Per-wavelength differences between table ``b`` and reference table ``a``.

    Attributes
    ----------
    name_a, name_b : str
        The tables' names.
    wavelength_nm : numpy.ndarray, shape (n_wavelength,)
        The common wavelengths. [nm]
    theta_deg : numpy.ndarray, shape (n_theta,)
        The angles compared. [deg]
    forward_peak_ratio : numpy.ndarray
        ``P_b(0 deg) / P_a(0 deg)``. [-]
    g_a, g_b : numpy.ndarray
        Asymmetry parameters of the two tables (as stored in them). [-]
    median_rel_diff, max_rel_diff : numpy.ndarray
        Median and largest over angle of ``|P_b - P_a| / P_a``. [-]
    interpolated : bool
        Whether the phase functions were interpolated (linearly in angle,
        :meth:`dustoptics.table.Table.phase_at`) onto ``theta_deg``.
    """

    name_a: str
    name_b: str
    wavelength_nm: np.ndarray
    theta_deg: np.ndarray
    forward_peak_ratio: np.ndarray
    g_a: np.ndarray
    g_b: np.ndarray
    median_rel_diff: np.ndarray
    max_rel_diff: np.ndarray
    interpolated: bool = False

    def __post_init__(self) -> None:
        for key in (
            "wavelength_nm",
            "theta_deg",
            "forward_peak_ratio",
            "g_a",
            "g_b",
            "median_rel_diff",
            "max_rel_diff",
        ):
            object.__setattr__(self, key, _readonly(getattr(self, key)))

    _COLUMNS = (
        "wavelength_nm",
        "forward_peak_ratio",
        "g_a",
        "g_b",
        "median_rel_diff",
        "max_rel_diff",
    )

    def to_frame(self) -> Any:
        """The comparison as a pandas DataFrame, one row per wavelength.

        Columns ``wavelength_nm`` [nm], ``forward_peak_ratio``, ``g_a``,
        ``g_b``, ``median_rel_diff`` and ``max_rel_diff`` [-].  Needs pandas
        (the ``pandas`` extra).
        """
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("to_frame needs pandas: pip install 'dustoptics[pandas]'") from None

        return pd.DataFrame({key: np.array(getattr(self, key)) for key in self._COLUMNS})

    def to_text(self) -> str:
        """An aligned text table, one row per wavelength; differences in percent."""
        how = (
            f"linear interpolation onto {self.theta_deg.size} angles"
            if self.interpolated
            else f"{self.theta_deg.size} angles"
        )
        lines = [
            f"b = {self.name_b!r} against a = {self.name_a!r} ({how})",
            (
                f"{'wavelength':>10}  {'P_b/P_a(0)':>10}  {'g_a':>7}  {'g_b':>7}  "
                f"{'median |b-a|/a':>14}  {'max |b-a|/a':>11}"
            ),
            f"{'[nm]':>10}  {'[-]':>10}  {'[-]':>7}  {'[-]':>7}  {'[%]':>14}  {'[%]':>11}",
        ]
        for i, wl in enumerate(self.wavelength_nm):
            lines.append(
                f"{wl:>10.6g}  {self.forward_peak_ratio[i]:>10.4f}  {self.g_a[i]:>7.4f}  "
                f"{self.g_b[i]:>7.4f}  {100 * self.median_rel_diff[i]:>14.3f}  "
                f"{100 * self.max_rel_diff[i]:>11.3f}"
            )
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.to_text()


def _first_difference(name: str, a: np.ndarray, b: np.ndarray, unit: str) -> str:
    if a.size != b.size:
        return f"{name} grids differ: {a.size} values in a, {b.size} in b"
    i = int(np.flatnonzero(a != b)[0])
    return f"{name} grids differ: first at index {i}, {float(a[i])!r} {unit} in a, {float(b[i])!r} {unit} in b"


def compare_tables(a: Table, b: Table, *, theta_deg: ArrayLike | None = None) -> TableComparison:
    """Compare table ``b`` with reference table ``a``, wavelength by wavelength.

    Parameters
    ----------
    a : Table
        Reference table (the denominator of the ratios and relative differences).
    b : Table
        Table compared with it.
    theta_deg : array_like, optional
        Angles within [0, 180], including 0 (the forward peak), at which both
        tables are read by linear interpolation in angle (what a renderer
        does): use it to compare tables on different angle grids.  Default:
        the tables' own angles, which must then be identical. [deg]

    Returns
    -------
    TableComparison

    Raises
    ------
    ValueError
        If the wavelength grids differ, or the angle grids differ and
        ``theta_deg`` is not given (the message says which grid and where),
        or ``theta_deg`` is invalid.
    """
    for label, table in (("a", a), ("b", b)):
        if not isinstance(table, Table):
            raise TypeError(f"{label} must be a dustoptics Table; got {type(table).__name__}")
    if not np.array_equal(a.wavelength_nm, b.wavelength_nm):
        raise ValueError(_first_difference("wavelength_nm", a.wavelength_nm, b.wavelength_nm, "nm"))
    if theta_deg is None:
        if not np.array_equal(a.theta_deg, b.theta_deg):
            raise ValueError(
                _first_difference("theta_deg", a.theta_deg, b.theta_deg, "deg")
                + "; pass theta_deg= to compare both at common angles by linear interpolation"
            )
        theta = a.theta_deg
        pa, pb = a.phase, b.phase
        interpolated = False
    else:
        theta = np.array(theta_deg, dtype=np.float64)
        if theta.ndim != 1 or theta.size == 0 or theta[0] != 0.0:
            raise ValueError(
                f"theta_deg must be a 1-D array of angles starting at exactly 0 deg (the "
                f"forward peak); got {_show(theta_deg)}"
            )
        pa, pb = a.phase_at(theta), b.phase_at(theta)
        interpolated = True
    rel = np.abs(pb - pa) / pa
    return TableComparison(
        name_a=a.name,
        name_b=b.name,
        wavelength_nm=a.wavelength_nm,
        theta_deg=theta,
        forward_peak_ratio=pb[:, 0] / pa[:, 0],
        g_a=a.g,
        g_b=b.g,
        median_rel_diff=np.median(rel, axis=1),
        max_rel_diff=np.max(rel, axis=1),
        interpolated=interpolated,
    )


def table_differences(stored: Table, fresh: Table) -> list[str]:
    """What differs between two tables that should be the same (empty: the same table).

    The same table means: the same inputs (:attr:`Provenance.input_hash
    <dustoptics.table.Provenance.input_hash>`), the same grids, and numbers
    equal to :data:`SAME_TABLE_RTOL` relative (error estimates:
    :data:`ESTIMATE_RTOL`).  The software versions a table records are not
    compared: a table rebuilt by another version that gives the same numbers is
    the same table.  ``scripts/build_tables.py --check`` and ``dustoptics
    build`` (an existing file that holds the same table is up to date) use it.

    Examples
    --------
    >>> import dustoptics as do
    >>> t = do.build_preset("costa")
    >>> table_differences(t, t)
    []
    >>> table_differences(t, t.replace(g=t.g * (1 + 1e-6)))
    ['costa: g differs by up to 1.00e-06 relative']
    """
    name = fresh.name
    problems = []
    if stored.provenance.input_hash != fresh.provenance.input_hash:
        problems.append(
            f"{name}: inputs changed (input hash {stored.provenance.input_hash[:12]} "
            f"stored, {fresh.provenance.input_hash[:12]} now)"
        )
    for grid in ("wavelength_nm", "theta_deg"):
        if not np.array_equal(stored.quantity(grid), fresh.quantity(grid)):
            problems.append(f"{name}: {grid} grid changed")
            return problems
    for key in _SAME_TABLE_ARRAYS:
        a, b = stored.quantity(key), fresh.quantity(key)
        if (a is None) != (b is None):
            problems.append(f"{name}: {key} present in one table only")
        elif a is not None and not np.allclose(
            a,
            b,
            rtol=ESTIMATE_RTOL if key.endswith("error_estimate") else SAME_TABLE_RTOL,
            atol=0.0,
        ):
            worst = float(np.max(np.abs(a - b) / np.maximum(np.abs(b), np.finfo(float).tiny)))
            problems.append(f"{name}: {key} differs by up to {worst:.2e} relative")
    return problems
