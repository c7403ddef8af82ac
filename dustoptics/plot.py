"""Figures of a :class:`~dustoptics.table.Table`: phase functions, a wavelength x angle map, spectra.

Optional: needs matplotlib (``pip install 'dustoptics[plot]'``).  The package
imports without it; each function imports matplotlib when called and raises
:class:`ImportError` naming the extra when it is missing.

Every function returns a :class:`matplotlib.figure.Figure` built with the
object-oriented API (no :mod:`matplotlib.pyplot`), so no GUI backend is
started, no global figure registry is touched and no ``rcParams`` are changed;
the caller's style settings apply.  :func:`save` writes a figure as PNG or SVG,
atomically and byte-for-byte reproducibly.

The figures show the table's own numbers: angles [deg] and wavelengths [nm] of
its grids, the phase function [sr^-1], cross-sections [um^2], albedo and g.
Nothing is interpolated: a wavelength asked for must be one of the table's.

- :func:`phase_function`: P(theta) for chosen wavelengths, log scale, as a
  Cartesian plot or a half-disc polar plot (forward scattering to the right).
- :func:`phase_map`: P over wavelength x scattering angle as a colour map with
  a logarithmic colour scale and contour lines at every decade, like figure 4.5
  of the seed thesis (Meyran 2022).
- :func:`spectra`: cross-sections, single-scattering albedo and asymmetry
  parameter against wavelength (only g for a phase-function-only table).
- :func:`save`: write a figure to ``.png`` or ``.svg``.
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from dustoptics._validation import as_float_array
from dustoptics.io._atomic import write_files
from dustoptics.table import Table

if TYPE_CHECKING:  # pragma: no cover - typing only
    from matplotlib.figure import Figure

__all__ = [
    "MAX_DEFAULT_WAVELENGTHS",
    "SAVE_FORMATS",
    "phase_function",
    "phase_map",
    "save",
    "spectra",
]

#: File suffixes :func:`save` accepts and the matplotlib format of each.
SAVE_FORMATS: dict[str, str] = {".png": "png", ".svg": "svg"}

#: How many wavelengths :func:`phase_function` draws when none are chosen.
MAX_DEFAULT_WAVELENGTHS = 7

#: Salt of the ids in SVG output; a fixed value makes the ids reproducible.
_SVG_HASHSALT = "dustoptics"

#: Tolerance (relative) within which a requested wavelength matches the grid:
#: the round-off of a value written as text and read back, nothing more.
_WAVELENGTH_RTOL = 1e-9

_INSTALL_HINT = "install the plot extra: pip install 'dustoptics[plot]'"

_LABEL_THETA = "scattering angle θ [deg]"
_LABEL_WAVELENGTH = "wavelength λ [nm]"
_LABEL_PHASE = "phase function P [sr$^{-1}$]"
_LABEL_CROSS_SECTION = "cross-section per particle [µm$^2$]"
_LABEL_SSA = "single-scattering albedo [-]"
_LABEL_G = "asymmetry parameter g [-]"


# ---------------------------------------------------------------- helpers


def _matplotlib() -> Any:
    """Import matplotlib (and the parts used here), or fail naming the extra."""
    try:
        import matplotlib
        import matplotlib.colors
        import matplotlib.figure
    except ImportError as exc:
        raise ImportError(f"dustoptics.plot needs matplotlib; {_INSTALL_HINT}") from exc
    return matplotlib


def _check_table(table: Any) -> Table:
    if not isinstance(table, Table):
        raise TypeError(f"table must be a dustoptics.table.Table; got {type(table).__name__}")
    return table


def _fmt(values: Any) -> str:
    """Wavelengths as short text: ``"550"``, ``"550, 560"``."""
    return ", ".join(f"{float(v):g}" for v in np.atleast_1d(values))


def _grid_text(grid: np.ndarray) -> str:
    if grid.size == 1:
        return f"1 value, {grid[0]:g} nm"
    return f"{grid.size} values, {grid[0]:g}-{grid[-1]:g} nm"


def _wavelength_indices(table: Table, wavelengths_nm: Any) -> np.ndarray:
    """Indices into the table's wavelength grid of the requested wavelengths.

    ``None`` selects at most :data:`MAX_DEFAULT_WAVELENGTHS` wavelengths
    evenly spaced in index, always including the first and the last.
    """
    grid = table.wavelength_nm
    if wavelengths_nm is None:
        count = min(grid.size, MAX_DEFAULT_WAVELENGTHS)
        return np.unique(np.round(np.linspace(0, grid.size - 1, count)).astype(np.int64))
    requested = as_float_array("wavelengths_nm", wavelengths_nm)
    requested = np.atleast_1d(requested)
    if requested.ndim != 1 or requested.size == 0:
        raise ValueError(
            "wavelengths_nm must be one wavelength or a non-empty 1-D sequence [nm]; "
            f"got shape {requested.shape}"
        )
    indices: list[int] = []
    for value in requested:
        match = np.flatnonzero(np.abs(grid - value) <= _WAVELENGTH_RTOL * grid)
        if match.size == 0:
            above = int(np.searchsorted(grid, value))
            nearest = grid[max(above - 1, 0) : above + 1]
            raise ValueError(
                f"wavelengths_nm: {value:g} nm is not in the table's wavelength grid "
                f"({_grid_text(grid)}); nearest in the grid: {_fmt(nearest)} nm "
                "(plots show tabulated values only, nothing is interpolated)"
            )
        if int(match[0]) not in indices:
            indices.append(int(match[0]))
    return np.asarray(indices, dtype=np.int64)


def _edges(
    centres: np.ndarray, *, low: float | None = None, high: float | None = None
) -> np.ndarray:
    """Cell edges around grid points: midpoints inside, half a spacing outside.

    ``low`` and ``high`` clip the outer edges (the angle grid ends at 0 and 180
    deg, so its end cells are half cells).  A single point gets a cell of
    +-1 % of its value.
    """
    if centres.size == 1:
        edges = np.array([centres[0] * 0.99, centres[0] * 1.01])
    else:
        mid = 0.5 * (centres[1:] + centres[:-1])
        edges = np.concatenate(
            ([centres[0] - (mid[0] - centres[0])], mid, [centres[-1] + (centres[-1] - mid[-1])])
        )
    if low is not None:
        edges[0] = max(edges[0], low)
    if high is not None:
        edges[-1] = min(edges[-1], high)
    return edges


def _new_figure(mpl: Any, *, size: tuple[float, float]) -> Figure:
    # A bare Figure (no pyplot): not registered anywhere, collected with its owner.
    return mpl.figure.Figure(figsize=size, layout="constrained")


# ---------------------------------------------------------------- figures


def phase_function(table: Table, *, wavelengths_nm: Any = None, polar: bool = False) -> Figure:
    """Phase function against scattering angle for chosen wavelengths, log scale.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table to plot.
    wavelengths_nm : float or sequence of float, optional
        Wavelengths to draw, each one of ``table.wavelength_nm`` (equal to
        within 1e-9 relative, the round-off of a value read from text); drawn
        in the order given, repeats once.  Default: at most
        :data:`MAX_DEFAULT_WAVELENGTHS` wavelengths evenly spaced over the
        grid's indices, including the first and the last. [nm]
    polar : bool, optional
        False (default): P [sr^-1] on a logarithmic y axis against theta
        [deg].  True: a half-disc polar plot, angle theta (0 = forward, to the
        right), logarithmic radius P [sr^-1].

    Returns
    -------
    matplotlib.figure.Figure
        One axes with one line per wavelength (in the order drawn), labelled
        ``"<wavelength> nm"``, whose data are the table's angles (in degrees;
        in radians for ``polar=True``) and phase values, unaltered.  Zero values
        are not drawn on the log scale.

    Raises
    ------
    ValueError
        A requested wavelength is not in the table's grid (the message lists
        the nearest grid wavelengths), or ``wavelengths_nm`` is empty.
    ImportError
        matplotlib is not installed.

    Examples
    --------
    >>> from dustoptics import plot
    >>> fig = plot.phase_function(table, wavelengths_nm=[450, 550, 650])  # doctest: +SKIP
    >>> plot.save(fig, "phase.svg")                                       # doctest: +SKIP
    """
    table = _check_table(table)
    indices = _wavelength_indices(table, wavelengths_nm)
    mpl = _matplotlib()
    if polar:
        return _polar_phase_function(mpl, table, indices)
    fig = _new_figure(mpl, size=(7.0, 4.5))
    ax: Any = fig.add_subplot()
    for i, colour in zip(indices, _wavelength_colours(mpl, table, indices)):
        ax.plot(
            table.theta_deg,
            table.phase[i],
            color=colour,
            linewidth=1.2,
            label=f"{table.wavelength_nm[i]:g} nm",
        )
    ax.set_yscale("log", nonpositive="mask")
    ax.set_xlim(0.0, 180.0)
    ax.set_xticks(np.arange(0.0, 181.0, 30.0))
    ax.set_xlabel(_LABEL_THETA)
    ax.set_ylabel(_LABEL_PHASE)
    ax.grid(True, which="major", linewidth=0.4, alpha=0.5)
    ax.legend(title="wavelength", fontsize="small")
    ax.set_title(f"{table.name}: phase function")
    return fig


def _wavelength_colours(mpl: Any, table: Table, indices: np.ndarray) -> list[Any]:
    """viridis by wavelength, the same colour for a wavelength in every figure."""
    wl = table.wavelength_nm
    cmap = mpl.colormaps["viridis"]
    span = wl[-1] - wl[0]
    return [cmap(0.0 if span == 0 else 0.9 * (wl[i] - wl[0]) / span) for i in indices]


def _polar_phase_function(mpl: Any, table: Table, indices: np.ndarray) -> Figure:
    """Half-disc polar plot: theta from 0 (forward, right) to 180 deg, log radius P.

    The half disc fills the figure: matplotlib places a partial polar wedge
    inside its axes box by its own rules, so the wedge is measured once drawn
    and the box moved and scaled to put the wedge on the intended rectangle
    (the box's empty part then lies outside the figure).  The radius runs
    over whole decades from the decade below the smallest value drawn, and its
    labels sit along the backward (180 deg) baseline, where the curves stay
    near the centre, one label per decade.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    width_in, height_in = 8.0, 4.6
    fig = mpl.figure.Figure(figsize=(width_in, height_in))
    FigureCanvasAgg(fig)
    disc_in = 5.3  # diameter of the half disc [in]
    # The half disc's rectangle (figure fraction): left, baseline, width, height.
    box_w, box_h = disc_in / width_in, disc_in / 2 / height_in
    target = (0.05, 0.2, box_w, box_h)
    centre = (target[0] + box_w / 2, target[1])  # baseline centre
    ax: Any = fig.add_axes((0.1, 0.1, 0.5, 0.5), projection="polar")
    drawn = table.phase[indices]
    positive = drawn[drawn > 0]
    low = 10.0 ** np.floor(np.log10(positive.min())) if positive.size else 1e-3
    high = 10.0 ** np.ceil(np.log10(positive.max())) if positive.size else 1.0
    theta = np.deg2rad(table.theta_deg)
    for i, colour in zip(indices, _wavelength_colours(mpl, table, indices)):
        ax.plot(
            theta,
            table.phase[i],
            color=colour,
            linewidth=1.2,
            label=f"{table.wavelength_nm[i]:g} nm",
        )
    ax.set_thetamin(0.0)
    ax.set_thetamax(180.0)
    fig.canvas.draw()  # the wedge's path is set when drawn
    wedge = ax.patch.get_window_extent(fig.canvas.get_renderer())
    wedge = wedge.transformed(fig.transFigure.inverted())
    pos = ax.get_position()
    sx, sy = target[2] / wedge.width, target[3] / wedge.height
    ax.set_position(
        (
            target[0] - (wedge.x0 - pos.x0) * sx,
            target[1] - (wedge.y0 - pos.y0) * sy,
            pos.width * sx,
            pos.height * sy,
        )
    )
    ax.set_rscale("log")
    ax.set_rlim(low, high)
    decades = 10.0 ** np.arange(np.log10(low), np.log10(high) + 0.5)
    ax.set_thetagrids(np.arange(0.0, 181.0, 30.0))
    ax.set_rticks(decades[1:])
    # A wedge's radial labels go on its edge spines: the end spine is theta = 180 deg.
    ax.tick_params(axis="y", labelsize="small", labelleft=False, labelright=True)
    ax.grid(True, linewidth=0.4, alpha=0.6)
    # Axis labels and title where the figure has room (the axes box reaches past it).
    ax.set_xlabel(_LABEL_THETA + ", 0 = forward", fontsize="small")
    ax.xaxis.set_label_coords(centre[0] + box_w / 4, centre[1] - 0.1, transform=fig.transFigure)
    ax.set_ylabel(_LABEL_PHASE + ", log radius", fontsize="small", rotation=0)
    ax.yaxis.set_label_coords(centre[0] - box_w / 4, centre[1] - 0.1, transform=fig.transFigure)
    for label in (ax.xaxis.label, ax.yaxis.label):
        label.set_verticalalignment("top")
        label.set_horizontalalignment("center")
    position = ax.get_position()
    ax.set_title(
        f"{table.name}: phase function", y=(0.93 - position.y0) / position.height, va="bottom"
    )
    ax.legend(
        title="wavelength",
        loc="upper left",
        bbox_to_anchor=(centre[0] + box_w / 2 + 0.03, centre[1] + box_h),
        bbox_transform=fig.transFigure,
        fontsize="small",
    )
    return fig


def phase_map(table: Table) -> Figure:
    """Phase function over wavelength and scattering angle, logarithmic colour scale.

    Each grid point (theta, lambda) of the table is one cell of the colour map
    (no interpolation); white contour lines mark every decade of P.  This is
    the view of figure 4.5 of the seed thesis (Meyran 2022).

    Parameters
    ----------
    table : dustoptics.table.Table
        The table to plot.

    Returns
    -------
    matplotlib.figure.Figure
        A map axes (x: scattering angle [deg], y: wavelength [nm]) holding a
        :class:`~matplotlib.collections.QuadMesh` of ``table.phase`` with a
        :class:`~matplotlib.colors.LogNorm` from its smallest positive to its
        largest value (zeros are left blank), and a colour-bar axes labelled
        with the phase function's unit [sr^-1].  The mesh is rasterized in
        vector output so that an SVG stays small.

    Raises
    ------
    ImportError
        matplotlib is not installed.

    Examples
    --------
    >>> from dustoptics import plot
    >>> plot.save(plot.phase_map(table), "map.png")      # doctest: +SKIP
    """
    table = _check_table(table)
    mpl = _matplotlib()
    phase = table.phase
    positive = phase[phase > 0]
    vmin, vmax = float(positive.min()), float(positive.max())
    if vmin == vmax:  # a flat (isotropic) phase function: give the norm a range
        vmin, vmax = vmin / 1.01, vmax * 1.01
    norm = mpl.colors.LogNorm(vmin=vmin, vmax=vmax)
    fig = _new_figure(mpl, size=(7.0, 4.5))
    ax = fig.add_subplot()
    theta, wl = table.theta_deg, table.wavelength_nm
    mesh = ax.pcolormesh(
        _edges(theta, low=0.0, high=180.0),
        _edges(wl),
        np.ma.masked_less_equal(phase, 0.0),
        norm=norm,
        cmap="viridis",
        shading="flat",
        rasterized=True,
    )
    cbar = fig.colorbar(mesh, ax=ax)
    cbar.set_label(_LABEL_PHASE)
    decades = 10.0 ** np.arange(np.ceil(np.log10(vmin)), np.floor(np.log10(vmax)) + 1)
    if wl.size >= 2 and decades.size:
        lines = ax.contour(theta, wl, phase, levels=decades, colors="white", linewidths=0.6)
        cbar.add_lines(lines)
    ax.set_xlim(0.0, 180.0)
    ax.set_xticks(np.arange(0.0, 181.0, 30.0))
    ax.set_xlabel(_LABEL_THETA)
    ax.set_ylabel(_LABEL_WAVELENGTH)
    ax.set_title(f"{table.name}: phase function P(θ, λ)")
    return fig


def spectra(table: Table) -> Figure:
    """Cross-sections, single-scattering albedo and asymmetry parameter against wavelength.

    Parameters
    ----------
    table : dustoptics.table.Table
        The table to plot.

    Returns
    -------
    matplotlib.figure.Figure
        For a table with cross-sections, three axes sharing the wavelength
        axis [nm], top to bottom: extinction, scattering and absorption
        cross-sections per particle [um^2] (lines labelled ``"extinction"``,
        ``"scattering"``, ``"absorption"``), the single-scattering albedo [-]
        and g [-].  For a phase-function-only table, one axes with g [-],
        whose title says that the table has no cross-sections.  Every line's
        data are the table's wavelengths and values, unaltered.

    Raises
    ------
    ImportError
        matplotlib is not installed.

    Examples
    --------
    >>> from dustoptics import plot
    >>> plot.save(plot.spectra(table), "spectra.png")    # doctest: +SKIP
    """
    table = _check_table(table)
    mpl = _matplotlib()
    wl = table.wavelength_nm
    style: dict[str, Any] = {"marker": "o", "markersize": 2.5, "linewidth": 1.2}
    if table.cross_sections is None:
        fig = _new_figure(mpl, size=(7.0, 3.5))
        ax_g = fig.add_subplot()
        ax_g.plot(wl, table.g, color="C0", label="g", **style)
        ax_g.set_ylabel(_LABEL_G)
        ax_g.set_xlabel(_LABEL_WAVELENGTH)
        ax_g.grid(True, linewidth=0.4, alpha=0.5)
        ax_g.set_title(
            f"{table.name}: asymmetry parameter\n(phase function only: the table has no cross-sections)"
        )
        return fig
    fig = _new_figure(mpl, size=(7.0, 7.5))
    ax_c, ax_w, ax_g = fig.subplots(3, 1, sharex=True)
    ax_c.plot(wl, table.cross_sections.cext_um2, color="C0", label="extinction", **style)
    ax_c.plot(wl, table.cross_sections.csca_um2, color="C1", label="scattering", **style)
    ax_c.plot(wl, table.cabs_um2, color="C3", label="absorption", **style)
    ax_c.set_ylim(bottom=0.0)
    ax_c.set_ylabel(_LABEL_CROSS_SECTION)
    ax_c.legend(fontsize="small")
    ax_c.set_title(f"{table.name}: cross-sections, albedo and asymmetry parameter")
    ax_w.plot(wl, table.ssa, color="C2", label="albedo", **style)
    ax_w.set_ylabel(_LABEL_SSA)
    ax_g.plot(wl, table.g, color="C4", label="g", **style)
    ax_g.set_ylabel(_LABEL_G)
    ax_g.set_xlabel(_LABEL_WAVELENGTH)
    for ax in (ax_c, ax_w, ax_g):
        ax.grid(True, linewidth=0.4, alpha=0.5)
    return fig


# ---------------------------------------------------------------- output


def _render(figure: Any, fmt: str) -> bytes:
    """The figure's file content in ``fmt``, reproducible for the same figure."""
    mpl = _matplotlib()
    buffer = io.BytesIO()
    if fmt == "svg":
        # SVG ids are hashes salted with rcParams["svg.hashsalt"], a random
        # salt when unset; savefig takes no option for it, so it is set for
        # this one call only and restored on exit.
        with mpl.rc_context({"svg.hashsalt": _SVG_HASHSALT}):
            figure.savefig(buffer, format="svg", metadata={"Date": None})
    else:
        figure.savefig(buffer, format="png", metadata={"Software": None})
    return buffer.getvalue()


def save(figure: Figure, path: str | os.PathLike[str], *, overwrite: bool = False) -> Path:
    """Write a figure to a PNG or SVG file, atomically and reproducibly.

    Parameters
    ----------
    figure : matplotlib.figure.Figure
        A figure from this module (or any matplotlib figure).
    path : path-like
        Target file; its suffix (``.png`` or ``.svg``, any case) picks the
        format.  Missing directories are created.
    overwrite : bool, optional
        Replace an existing file.  Default False.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ValueError
        The suffix is not one of :data:`SAVE_FORMATS`.
    FileExistsError
        ``path`` exists and ``overwrite`` is False.
    ImportError
        matplotlib is not installed.

    Notes
    -----
    The whole file is rendered in memory and written with the package's one
    atomic-write mechanism (:func:`dustoptics.io._atomic.write_files`): a
    temporary file in the target directory, moved into place with
    :func:`os.replace`, so the target is never left partly written.  Output
    is reproducible: the same figure (hence the same table, with the same
    matplotlib, fonts and style) gives the same bytes.  PNG files carry no ``Software`` entry; SVG files
    carry no date and their element ids use a fixed salt
    (``svg.hashsalt``, set for the duration of the call only).
    """
    target = Path(path)
    fmt = SAVE_FORMATS.get(target.suffix.lower())
    if fmt is None:
        allowed = ", ".join(repr(s) for s in SAVE_FORMATS)
        raise ValueError(f"path must end in one of {allowed}; got {str(path)!r}")
    mpl = _matplotlib()
    if not isinstance(figure, mpl.figure.Figure):
        raise TypeError(f"figure must be a matplotlib.figure.Figure; got {type(figure).__name__}")
    # Imported here: dustoptics.io loads every format's writer, which plotting does not need.

    write_files({target: _render(figure, fmt)}, overwrite=bool(overwrite))
    return target
