"""dustoptics: exact, reproducible optics of atmospheric dust for renderers.

The data flow reads one way: materials and mixing rules give a refractive index
m = n + i k; a size distribution gives n(r); :mod:`dustoptics.scattering.quadrature` places
deterministic radius nodes; :mod:`dustoptics.scattering.mie` computes the spheres; and
:func:`dustoptics.scattering.optics.compute_optics` averages them into a converged table
over wavelength and scattering angle.  :mod:`dustoptics.scattering.phase` holds the
analytic phase functions and blending, :mod:`dustoptics.models.config` and
:mod:`dustoptics.models.presets` the named models, :mod:`dustoptics.table` the data
model with provenance, :mod:`dustoptics.io` the renderers' formats,
:mod:`dustoptics.atmosphere.gases`, :mod:`dustoptics.atmosphere.column`,
:mod:`dustoptics.atmosphere.parametric` and :mod:`dustoptics.atmosphere.sets` the other
constituents and whole atmosphere sets, and :mod:`dustoptics.cli` the
command line.

>>> import dustoptics as do
>>> dist = do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
>>> t = do.compute_optics(do.mars_dust(), dist)     # doctest: +SKIP
"""

from importlib.metadata import PackageNotFoundError, version as _version

from dustoptics import atmosphere, colour, compare, io, models, particles, scattering, table
from dustoptics.atmosphere import column, gases, parametric
from dustoptics.models import config, presets
from dustoptics.particles import materials, mixing, sizedist
from dustoptics.scattering import mie, optics, phase, quadrature
from dustoptics.compare import compare_tables
from dustoptics.models.config import build_table, load_config
from dustoptics.models.presets import build_preset, list_presets
from dustoptics.table import Provenance, Source, Table
from dustoptics.particles.materials import (
    ConstantIndex,
    GasFormulaIndex,
    OrientationAverage,
    RefractiveIndex,
    TabulatedIndex,
    get_material,
    list_materials,
    read_index_csv,
)
from dustoptics.particles.mixing import Mixture, bruggeman, mars_dust, maxwell_garnett
from dustoptics.scattering.optics import ConvergenceWarning, OpticsTable, compute_optics
from dustoptics.scattering.phase import (
    costa2021_mars_dhg,
    cornette_shanks1992,
    double_henyey_greenstein,
    henyey_greenstein,
    hybrid,
    renormalize,
    sphere_integral,
)
from dustoptics.scattering.quadrature import QuadratureSettings
from dustoptics.particles.sizedist import (
    Gamma,
    LogNormal,
    ModifiedGamma,
    ModifiedLogNormal,
    Monodisperse,
    MultiModal,
    SizeDistribution,
)

try:
    __version__ = _version("dustoptics")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.0.0+unknown"

__all__ = [
    "atmosphere",
    "models",
    "particles",
    "scattering",
    "colour",
    "column",
    "compare",
    "config",
    "gases",
    "io",
    "parametric",
    "presets",
    "table",
    "compare_tables",
    "build_table",
    "load_config",
    "build_preset",
    "list_presets",
    "Provenance",
    "Source",
    "Table",
    "materials",
    "mie",
    "mixing",
    "optics",
    "phase",
    "quadrature",
    "sizedist",
    "ConstantIndex",
    "GasFormulaIndex",
    "OrientationAverage",
    "RefractiveIndex",
    "TabulatedIndex",
    "get_material",
    "list_materials",
    "read_index_csv",
    "Mixture",
    "bruggeman",
    "mars_dust",
    "maxwell_garnett",
    "ConvergenceWarning",
    "OpticsTable",
    "compute_optics",
    "costa2021_mars_dhg",
    "cornette_shanks1992",
    "double_henyey_greenstein",
    "henyey_greenstein",
    "hybrid",
    "renormalize",
    "sphere_integral",
    "QuadratureSettings",
    "Gamma",
    "LogNormal",
    "ModifiedGamma",
    "ModifiedLogNormal",
    "Monodisperse",
    "MultiModal",
    "SizeDistribution",
    "__version__",
]
