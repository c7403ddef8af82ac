"""dustoptics: exact, reproducible optics of atmospheric dust for renderers.

The data flow reads one way: materials and mixing rules give a refractive index
m = n + i k; a size distribution gives n(r); :mod:`dustoptics.scattering.quadrature` places
deterministic radius nodes; :mod:`dustoptics.scattering.mie` computes the spheres; and
:func:`dustoptics.scattering.optics.compute_optics` averages them into a converged table
over wavelength and scattering angle.  :mod:`dustoptics.scattering.phase` holds the
analytic phase functions, :mod:`dustoptics.scattering.tabulated_phase` the blending of
tabulated ones, :mod:`dustoptics.models.config` and
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

from dustoptics.cli import _interrupt  # noqa: F401, I001  (first: Ctrl-C while the command imports)
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _version

try:
    __version__ = _version("dustoptics")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.0.0+unknown"

# Before any kernel is defined: where numba caches them (never inside site-packages).
from dustoptics import _numba_cache

_numba_cache.configure(__version__)

# The command `dustoptics build` on an empty numba cache: the kernels start compiling
# on the other cores now, while this process imports (cli._prestart; nothing otherwise).
from dustoptics.cli import _prestart

_prestart.start()

from dustoptics import atmosphere, colour, compare, io, models, particles, scattering, sky, table
from dustoptics.atmosphere import column, gases, parametric
from dustoptics.compare import compare_tables
from dustoptics.io.tables.netcdf import open_table
from dustoptics.models import config, presets
from dustoptics.models.compute import build_table
from dustoptics.models.files import load_config
from dustoptics.models.presets import build_preset, list_presets
from dustoptics.particles import materials, mixing, sizedist
from dustoptics.particles.catalogue import get_material, list_materials
from dustoptics.particles.coated import CoatedSphere
from dustoptics.particles.custom_sizedist import (
    DensityDistribution,
    MultiModal,
    TabulatedDistribution,
)
from dustoptics.particles.materials import (
    ConstantIndex,
    GasFormulaIndex,
    OrientationAverage,
    RefractiveIndex,
    TabulatedIndex,
    read_index_csv,
)
from dustoptics.particles.mixing import (
    MARS_DUST_DENSITY_KG_M3,
    Mixture,
    bruggeman,
    mars_dust,
    maxwell_garnett,
)
from dustoptics.particles.sizedist import (
    DeirmendjianGamma,
    Gamma,
    LogNormal,
    ModifiedGamma,
    ModifiedLogNormal,
    Monodisperse,
    PowerLaw,
    SizeDistribution,
    Truncated,
)
from dustoptics.scattering import expansion, mie, optics, phase, quadrature
from dustoptics.scattering.optics import ConvergenceWarning, compute_optics
from dustoptics.scattering.phase import (
    cornette_shanks1992,
    costa2021_mars_dhg,
    double_henyey_greenstein,
    henyey_greenstein,
)
from dustoptics.scattering.quadrature import QuadratureSettings
from dustoptics.scattering.tabulated_phase import hybrid, renormalize, sphere_integral
from dustoptics.table import Provenance, Source, Table, TableDerivatives

__all__ = [
    "MARS_DUST_DENSITY_KG_M3",
    "CoatedSphere",
    "ConstantIndex",
    "ConvergenceWarning",
    "DeirmendjianGamma",
    "DensityDistribution",
    "Gamma",
    "GasFormulaIndex",
    "LogNormal",
    "Mixture",
    "ModifiedGamma",
    "ModifiedLogNormal",
    "Monodisperse",
    "MultiModal",
    "OrientationAverage",
    "PowerLaw",
    "Provenance",
    "QuadratureSettings",
    "RefractiveIndex",
    "SizeDistribution",
    "Source",
    "Table",
    "TableDerivatives",
    "TabulatedDistribution",
    "TabulatedIndex",
    "Truncated",
    "__version__",
    "atmosphere",
    "bruggeman",
    "build_preset",
    "build_table",
    "colour",
    "column",
    "compare",
    "compare_tables",
    "compute_optics",
    "config",
    "cornette_shanks1992",
    "costa2021_mars_dhg",
    "double_henyey_greenstein",
    "expansion",
    "gases",
    "get_material",
    "henyey_greenstein",
    "hybrid",
    "io",
    "list_materials",
    "list_presets",
    "load_config",
    "mars_dust",
    "materials",
    "maxwell_garnett",
    "mie",
    "mixing",
    "models",
    "open_table",
    "optics",
    "parametric",
    "particles",
    "phase",
    "presets",
    "quadrature",
    "read_index_csv",
    "renormalize",
    "scattering",
    "sizedist",
    "sky",
    "sphere_integral",
    "table",
]
