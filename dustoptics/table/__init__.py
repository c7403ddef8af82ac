"""The table as data: one model for a computed optical table and its provenance.

Every exporter writes a :class:`Table` and every reader returns one, so a table
read back from any format has the same quantities, units and provenance as the
one that was written.  A table describes one constituent of an atmosphere (a
dust population, a gas): its phase function over wavelength and scattering
angle and, in records present whole or not at all, its mean cross-sections
per particle (:class:`CrossSections`, with the number density that gives its
volume coefficients), the record of the quadrature that computed it
(:class:`QuadratureRecord`), its scattering matrix (:class:`ScatteringMatrix`),
its expansion in generalized spherical functions (:class:`Expansion`) and
derivatives (:class:`TableDerivatives`).  ``table.expansion is not None`` says
whether a table has one.

One concept, the table, in one package of small modules: :mod:`.schema` (every
quantity's name, unit and meaning), :mod:`.provenance`, :mod:`.components` (the
records), :mod:`.derivatives`, :mod:`.core` (:class:`Table`), :mod:`.conversion`
(xarray) and :mod:`.registry`.  The package's other modules import it and it
imports none of them (writers and the fitter register themselves here,
:func:`register_table_writer`, :func:`register_table_fitter`).

Stored quantities (and their units)
-----------------------------------
``wavelength_nm`` [nm], ``theta_deg`` [deg] (0 = forward scattering),
``phase`` [sr^-1] normalized so that 2 pi int_{-1}^{1} P dmu = 1,
``g`` [-] (asymmetry parameter of ``phase``); ``cext_um2`` and ``csca_um2``
[um^2] (mean cross-sections per particle), ``mean_geometric_cross_section_um2``
[um^2] (pi <r^2>) and ``number_density_per_m3`` [m^-3] in
:class:`CrossSections`; the quadrature's error estimates [-] and node counts
[-] in :class:`QuadratureRecord`; for tables computed by
:func:`~dustoptics.scattering.optics.compute_optics` also the refractive index
m = n + i k used at each wavelength [-].  :meth:`Table.quantity` reads any of
them by name.

Everything else is derived, never stored twice: ``cabs_um2 = cext - csca``,
``ssa = csca / cext``, ``qext = cext / (pi <r^2>)``, and
``beta_ext_per_m = N cext`` (and likewise for scattering and absorption), so a
file can never hold an albedo that disagrees with its cross-sections.
"""

from __future__ import annotations

from dustoptics.table.components import (
    CrossSections,
    Expansion,
    QuadratureRecord,
    ScatteringMatrix,
    alpha1_from_pmom,
    grouped_fields,
    pmom_from_alpha1,
)
from dustoptics.table.core import Table
from dustoptics.table.derivatives import TableDerivatives
from dustoptics.table.provenance import Provenance, Source, canonical_json, plain, software_versions
from dustoptics.table.registry import register_table_fitter, register_table_writer
from dustoptics.table.schema import (
    AEROSOL_STANDARD_NAMES,
    DEFAULT_NAME,
    DERIVED,
    PHASE_NORMALIZATION,
    SCHEMA,
    SOFTWARE,
    STANDARD_NAMES,
    UNITS,
)

__all__ = [
    "AEROSOL_STANDARD_NAMES",
    "DEFAULT_NAME",
    "DERIVED",
    "PHASE_NORMALIZATION",
    "SCHEMA",
    "SOFTWARE",
    "STANDARD_NAMES",
    "UNITS",
    "CrossSections",
    "Expansion",
    "Provenance",
    "QuadratureRecord",
    "ScatteringMatrix",
    "Source",
    "Table",
    "TableDerivatives",
    "alpha1_from_pmom",
    "canonical_json",
    "grouped_fields",
    "plain",
    "pmom_from_alpha1",
    "register_table_fitter",
    "register_table_writer",
    "software_versions",
]
