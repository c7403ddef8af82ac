"""The table a build configuration describes: :func:`build_table`.

A :class:`~dustoptics.models.config.BuildConfig` (:mod:`dustoptics.models.config`) is
turned into a :class:`dustoptics.table.Table`: the polydisperse Mie computation of
:func:`dustoptics.scattering.optics.compute_optics`, an analytic phase function sampled
at the table's angles, or Meyran 2022's hybrid blend of the two, with the provenance
that says what it was made from.

Tables
------
:func:`build_table` returns a :class:`dustoptics.table.Table`.  Its
``Provenance.inputs`` is :meth:`~dustoptics.models.config.BuildConfig.to_inputs`:
every computational parameter with the defaults filled in (not the name,
description, sources and choices, which label the table; they go into
``Provenance.sources`` and ``Provenance.notes``), so equivalent files (e.g.
``n_theta = 1801`` and ``theta_step_deg = 0.1``) give the same input hash.

Asymmetry parameter ``g``: for ``"mie"`` it is the quadrature's
``2 pi int P mu dmu`` of the Mie phase function.  For ``"hybrid"`` and analytic
models it is computed from the returned table, read as a renderer reads it
(linear in theta between samples), with the exact piecewise-linear quadrature
of :func:`dustoptics.scattering.tabulated_phase.sphere_integral`; the provenance notes give its
largest difference from the analytic formula.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from dustoptics._validation import check_budget
from dustoptics.models.config import _COSTA_SPECTRUM, BuildConfig
from dustoptics.scattering import phase as _phase
from dustoptics.scattering import tabulated_phase as _tabulated
from dustoptics.scattering.optics import (
    ConvergenceWarning,
    OpticsRequest,
    compute_request,
    optics_request,
)
from dustoptics.table import Provenance, Source, Table

__all__ = ["build_table", "mie_request"]


def _analytic_table(
    config: BuildConfig,
    name: str,
    params: Mapping[str, Any],
    wavelength_nm: np.ndarray,
    theta: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, Source]:
    """(renormalized table, analytic mean cosine per wavelength, its source)."""
    n = wavelength_nm.size
    if name == _COSTA_SPECTRUM:
        spectrum = _phase.costa2021_mars_dhg(wavelength_nm, outside=params["outside"])
        raw = _tabulated.tabulate(
            _phase.dhg_costa2021,
            theta_deg=theta,
            g1=spectrum.g1[:, None],
            g2=spectrum.g2[:, None],
            alpha=spectrum.alpha[:, None],
        )
        exact = spectrum.asymmetry()
        source = Source(name=_COSTA_SPECTRUM, role="phase function", citation=spectrum.citation)
    else:
        model = _phase.get_analytic_model(name)
        row = _tabulated.tabulate(model.phase, theta_deg=theta, **params)
        raw = np.broadcast_to(np.atleast_1d(row), (n, theta.size)).copy()
        exact = np.full(n, float(model.asymmetry(**params)))
        source = Source(name=name, role="phase function", citation=model.citation)
    return _tabulated.renormalize(raw, theta_deg=theta), exact, source


def mie_request(config: BuildConfig, *, wavelength_nm: np.ndarray | None = None) -> OpticsRequest:
    """The Mie computation a configuration describes, validated once.

    Parameters
    ----------
    config : BuildConfig
        A validated configuration whose phase function uses Mie theory
        (``config.phase.uses_mie``).
    wavelength_nm : numpy.ndarray, optional
        Some of its wavelengths instead of all (a sweep's chunk): each is
        computed on its own, so they equal the same wavelengths of the whole. [nm]

    Returns
    -------
    OpticsRequest
        For :func:`~dustoptics.scattering.optics.compute_request` (and
        :func:`~dustoptics.scattering.optics.check_cost`).
    """
    if config.material is None or config.size_distribution is None:
        raise ValueError(
            f"configuration {config.name!r} has no material and size distribution: "
            "its phase function is analytic, not a Mie computation"
        )
    assert config.optics.rtol is not None and config.optics.weighting is not None
    return optics_request(
        config.material.build(),
        config.size_distribution.build(),
        config.wavelengths_nm if wavelength_nm is None else wavelength_nm,
        config.theta_deg,
        rtol=config.optics.rtol,
        weighting=config.optics.weighting,
        cross_section_rtol=config.optics.cross_section_rtol,
        expansion=False if config.optics.expansion is None else config.optics.expansion,
        polarization=config.optics.polarization,
    )


def _add_sources(sources: list[Source], *extra: Source) -> None:
    cited = {s.citation for s in sources}
    for s in extra:
        if s.citation not in cited:
            sources.append(s)
            cited.add(s.citation)


def build_table(
    config: BuildConfig,
    *,
    workers: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    allow_large: bool = False,
    allow_unvalidated: bool = False,
) -> Table:
    """Compute the table a configuration describes.

    Parameters
    ----------
    config : BuildConfig
        A validated configuration (:func:`dustoptics.models.config.parse_config`,
        :func:`dustoptics.models.files.load_config`,
        :func:`dustoptics.models.presets.load_preset`).
    workers : int, optional
        Threads over wavelengths for the Mie computation (default: all cores);
        the result is the same to the bit for any count.
    progress : callable, optional
        Called as ``progress(done, total)`` with the number of wavelengths
        done, first with ``done = 0`` and last with ``done = total``, e.g. to
        print a progress line.  It does not change the result.
    allow_large : bool, optional
        Go ahead beyond the memory and work budget
        (:func:`dustoptics.scattering.optics.compute_optics`); default False.
    allow_unvalidated : bool, optional
        Go ahead, with a warning, where the size parameters or refractive
        indices leave the validated domain
        (:data:`dustoptics.scattering.domain.VALIDATED_DOMAIN`); default False,
        which raises :class:`~dustoptics.scattering.domain.OutsideDomainError`
        before any work.

    Returns
    -------
    Table
        ``Provenance.inputs`` is ``config.to_inputs()``; the sources are the
        configuration's plus those of the material, size distribution and
        analytic phase function; the notes are the configuration's choices,
        how g was obtained, and the messages of the package's warnings about
        the result (:class:`~dustoptics.scattering.optics.ConvergenceWarning`,
        :class:`~dustoptics.scattering.phase.ExtrapolationWarning`); every warning raised
        while building is re-issued to the caller.

    Raises
    ------
    ValueError
        Inputs the engine rejects (e.g. a wavelength outside a material's data).
    """
    if not isinstance(config, BuildConfig):
        raise TypeError(
            f"config must be a BuildConfig (see parse_config); got {type(config).__name__}"
        )
    wl = config.wavelengths_nm
    theta = config.theta_deg
    inputs = config.to_inputs()
    sources = list(config.sources)
    notes = list(config.choices)
    ph = config.phase
    # The table's own arrays (a Mie computation's estimate, grids and largest
    # sphere, is compute_optics's, before any of its work).
    check_budget(
        "build_table",
        8.0 * 8.0 * wl.size * theta.size,
        allow_large=allow_large,
        change=f"the table holds {wl.size} wavelengths x {theta.size} angles: use fewer",
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if ph.uses_mie:
            table = compute_request(
                mie_request(config),
                workers=workers,
                name=config.name,
                progress=progress,
                allow_large=allow_large,
                allow_unvalidated=allow_unvalidated,
            )
            _add_sources(sources, *table.provenance.sources)
            if ph.model == "hybrid":
                assert ph.analytic is not None and ph.weight is not None
                p_analytic, _, analytic_source = _analytic_table(
                    config, ph.analytic, ph.parameters, wl, theta
                )
                _add_sources(sources, analytic_source)
                p_mie = _tabulated.renormalize(table.phase, theta_deg=theta)
                blended = _tabulated.hybrid(p_mie, p_analytic, theta_deg=theta, weight=ph.weight)
                notes.append(
                    f"phase: hybrid renormalize((1 - w) P_mie + w P_{ph.analytic}) with w = {ph.weight:g}, "
                    "both tables first renormalized under linear interpolation in theta; g is the "
                    "mean cosine of the blended table (exact for linear interpolation in theta); "
                    "cross-sections and error estimates are the Mie computation's"
                )
                table = table.replace(
                    phase=blended, g=_tabulated.mean_cosine(blended, theta_deg=theta)
                )
            table = table.replace(
                cross_sections={"number_density_per_m3": config.number_density_per_m3}
            )
        else:
            assert ph.analytic is not None
            if progress is not None:
                progress(0, wl.size)
            p_analytic, exact, analytic_source = _analytic_table(
                config, ph.analytic, ph.parameters, wl, theta
            )
            _add_sources(sources, analytic_source)
            g = np.asarray(_tabulated.mean_cosine(p_analytic, theta_deg=theta), dtype=np.float64)
            notes.append(
                f"phase: {ph.analytic} sampled at the table's angles and renormalized under linear "
                "interpolation in theta; no cross-sections (phase function only); g is the mean "
                "cosine of that table (exact for linear interpolation in theta), at most "
                f"{float(np.max(np.abs(g - exact))):.2e} from the analytic formula"
            )
            table = Table(
                name=config.name,
                wavelength_nm=wl,
                theta_deg=theta,
                phase=p_analytic,
                g=g,
                provenance=Provenance(inputs=inputs, sources=tuple(sources)),
            )
            if progress is not None:
                progress(wl.size, wl.size)
    # The package's own warnings about the result go into the notes; all are re-issued.
    messages = [
        f"warning ({w.category.__name__}): {w.message}"
        for w in caught
        if issubclass(w.category, (ConvergenceWarning, _phase.ExtrapolationWarning))
    ]
    notes.extend(dict.fromkeys(messages))  # once each, in order
    provenance = table.provenance
    table = table.replace(
        provenance=Provenance(
            inputs=inputs,
            sources=tuple(sources),
            software=provenance.software,
            quadrature=provenance.quadrature,
            notes=tuple(notes),
        )
    )
    for w in caught:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return table
