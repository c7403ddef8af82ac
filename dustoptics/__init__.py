"""dustoptics: exact, reproducible optics of atmospheric dust for renderers.

The data flow reads one way: materials and mixing rules give a refractive index
m = n + i k; a size distribution gives n(r); :mod:`dustoptics.quadrature` places
deterministic radius nodes; :mod:`dustoptics.mie` computes the spheres; and
:func:`dustoptics.optics.compute_optics` averages them into a converged table
over wavelength and scattering angle.  :mod:`dustoptics.phase` holds the
analytic phase functions and blending, :mod:`dustoptics.config` and
:mod:`dustoptics.presets` the named models, :mod:`dustoptics.table` the data
model with provenance, :mod:`dustoptics.io` the renderers' formats,
:mod:`dustoptics.gases`, :mod:`dustoptics.column`,
:mod:`dustoptics.parametric` and :mod:`dustoptics.atmosphere` the other
constituents and whole atmosphere sets, and :mod:`dustoptics.cli` the
command line.

>>> import dustoptics as do
>>> dist = do.ModifiedGamma(r_eff_um=1.6, v_eff=0.2)
>>> t = do.compute_optics(do.mars_dust(), dist)     # doctest: +SKIP
"""

from importlib.metadata import PackageNotFoundError, version as _version

from dustoptics import (
    atmosphere,
    colour,
    column,
    compare,
    config,
    gases,
    io,
    materials,
    mie,
    mixing,
    optics,
    parametric,
    phase,
    presets,
    quadrature,
    sizedist,
    table,
)
from dustoptics.compare import compare_tables
from dustoptics.config import build_table, load_config
from dustoptics.presets import build_preset, list_presets
from dustoptics.table import Provenance, Source, Table
from dustoptics.materials import (
    ConstantIndex,
    GasFormulaIndex,
    OrientationAverage,
    RefractiveIndex,
    TabulatedIndex,
    get_material,
    list_materials,
    read_index_csv,
)
from dustoptics.mixing import Mixture, bruggeman, mars_dust, maxwell_garnett
from dustoptics.optics import ConvergenceWarning, OpticsTable, compute_optics
from dustoptics.phase import (
    costa2021_mars_dhg,
    cornette_shanks1992,
    double_henyey_greenstein,
    henyey_greenstein,
    hybrid,
    renormalize,
    sphere_integral,
)
from dustoptics.quadrature import QuadratureSettings
from dustoptics.sizedist import (
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
