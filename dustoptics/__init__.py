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
import importlib as _importlib
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _version
from typing import TYPE_CHECKING, Any

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

if TYPE_CHECKING:  # the names as type checkers and IDEs see them (loaded lazily below)
    from dustoptics import (
        atmosphere,
        colour,
        compare,
        io,
        models,
        particles,
        scattering,
        sky,
        table,
    )
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

# The public names load on first use (PEP 562): ``import dustoptics`` imports no
# numpy, scipy or numba, and a command imports only what it uses.  Name -> the module
# that defines it (a submodule name maps to itself).
_SUBMODULES = {
    "atmosphere": "dustoptics.atmosphere",
    "colour": "dustoptics.colour",
    "compare": "dustoptics.compare",
    "io": "dustoptics.io",
    "models": "dustoptics.models",
    "particles": "dustoptics.particles",
    "scattering": "dustoptics.scattering",
    "sky": "dustoptics.sky",
    "table": "dustoptics.table",
    "column": "dustoptics.atmosphere.column",
    "gases": "dustoptics.atmosphere.gases",
    "parametric": "dustoptics.atmosphere.parametric",
    "config": "dustoptics.models.config",
    "presets": "dustoptics.models.presets",
    "materials": "dustoptics.particles.materials",
    "mixing": "dustoptics.particles.mixing",
    "sizedist": "dustoptics.particles.sizedist",
    "expansion": "dustoptics.scattering.expansion",
    "mie": "dustoptics.scattering.mie",
    "optics": "dustoptics.scattering.optics",
    "phase": "dustoptics.scattering.phase",
    "quadrature": "dustoptics.scattering.quadrature",
}
_NAMES = {
    "dustoptics.compare": ("compare_tables",),
    "dustoptics.io.tables.netcdf": ("open_table",),
    "dustoptics.models.compute": ("build_table",),
    "dustoptics.models.files": ("load_config",),
    "dustoptics.models.presets": ("build_preset", "list_presets"),
    "dustoptics.particles.catalogue": ("get_material", "list_materials"),
    "dustoptics.particles.coated": ("CoatedSphere",),
    "dustoptics.particles.custom_sizedist": (
        "DensityDistribution",
        "MultiModal",
        "TabulatedDistribution",
    ),
    "dustoptics.particles.materials": (
        "ConstantIndex",
        "GasFormulaIndex",
        "OrientationAverage",
        "RefractiveIndex",
        "TabulatedIndex",
        "read_index_csv",
    ),
    "dustoptics.particles.mixing": (
        "MARS_DUST_DENSITY_KG_M3",
        "Mixture",
        "bruggeman",
        "mars_dust",
        "maxwell_garnett",
    ),
    "dustoptics.particles.sizedist": (
        "DeirmendjianGamma",
        "Gamma",
        "LogNormal",
        "ModifiedGamma",
        "ModifiedLogNormal",
        "Monodisperse",
        "PowerLaw",
        "SizeDistribution",
        "Truncated",
    ),
    "dustoptics.scattering.optics": ("ConvergenceWarning", "compute_optics"),
    "dustoptics.scattering.phase": (
        "cornette_shanks1992",
        "costa2021_mars_dhg",
        "double_henyey_greenstein",
        "henyey_greenstein",
    ),
    "dustoptics.scattering.quadrature": ("QuadratureSettings",),
    "dustoptics.scattering.tabulated_phase": ("hybrid", "renormalize", "sphere_integral"),
    "dustoptics.table": ("Provenance", "Source", "Table", "TableDerivatives"),
}
_LAZY = {**{n: m for m, names in _NAMES.items() for n in names}, **_SUBMODULES}

#: Imported before the first public name is served: they register Table.save's
#: netCDF writer and Table.fit's fitter, as an eager ``import dustoptics`` did.
_REGISTERING = ("dustoptics.scattering", "dustoptics.io.tables.netcdf")


def __getattr__(name: str) -> Any:
    """A public name, imported on first use (then cached in the module)."""
    module_name = _LAZY.get(name)
    if module_name is None:
        raise AttributeError(f"module 'dustoptics' has no attribute {name!r}")
    for registering in _REGISTERING:
        _importlib.import_module(registering)
    module = _importlib.import_module(module_name)
    value = module if name in _SUBMODULES else getattr(module, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


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
