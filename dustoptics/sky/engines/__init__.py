"""Rendering engines' own sky models, fitted to the exact sky, and their parameter files.

One module per engine holds its sky model (implemented from the engine's
shader source or published equations, cited with the version read) and its
format; :mod:`~dustoptics.sky.engines.core` holds the shared framework:

- :class:`~dustoptics.sky.engines.core.EngineModel`: one record per engine,
  registered once with :func:`~dustoptics.sky.engines.core.register_engine`
  into :data:`~dustoptics.sky.engines.core.ENGINES` (everything else, the
  command line's ``build mars|earth --format NAME`` and ``engines report``,
  reads that registry).  Its fields:

  ``name``
      the format name and key (``"threejs"``);
  ``title``, ``source``
      the engine and model, and the engine version and file read;
  ``parameters``
      the fitted :class:`~dustoptics.sky.engines.core.Parameter` s (engine's
      names, bounds, ``log`` for positive scales, unit);
  ``community_parameters``
      the subset adjusted for the community row (the exposure: anyone sets it);
  ``render(params, *, sun_elevation_deg, view_zenith_deg, view_azimuth_deg)``
      the engine's sky as linear sRGB, shape ``zenith.shape + (3,)``, per unit
      solar illuminance [sr^-1] (an engine without physical units carries an
      ``exposure`` parameter; a physical engine lit by a Sun of colour
      :func:`~dustoptics.sky.engines.core.sunlight_linear_srgb` and unit
      illuminance is already in these units); azimuths are measured from the
      Sun's, zenith angles from the local vertical, both in degrees and
      broadcast against each other; ``params`` is a flat mapping of floats
      (vectors as ``NAME_r``, ``NAME_g``, ``NAME_b``);
  ``initial(atmosphere)``, ``community(atmosphere)``
      every value ``render`` takes (fixed ones such as the planet radius
      included): the fit's start, and what people use today for that
      planet (the engine's Earth defaults with a dust tint for Mars);
  ``write(fit, out_dir, *, overwrite)``
      the engine's files for an :class:`~dustoptics.sky.engines.core.EngineFit`
      (atomically, :func:`dustoptics.io._atomic.write_files`), each with a
      comment block naming the engine version read and the fit's error.

- :func:`~dustoptics.sky.engines.core.reference_skies`: the exact spectral sky
  (:func:`dustoptics.sky.scene.sky_radiance`) as CIE XYZ on a coarse dome
  (zenith angles :data:`~dustoptics.sky.engines.core.DOME_ZENITH_DEG` plus the
  one 10 deg above the Sun, azimuths every 15 deg from the Sun's: about 12 x
  13 directions) at the Sun elevations
  :data:`~dustoptics.sky.engines.core.FIT_SUN_ELEVATIONS_DEG` (45, 20, 5 and
  0 deg), a few seconds each.
- :func:`~dustoptics.sky.engines.core.fit_engine`: the engine's parameters by
  least squares of the per-direction CIE Delta E 2000 over the dome and every
  Sun elevation (``kind="fitted"``), or the community row with only its
  exposure adjusted (``kind="community"``).
- :func:`~dustoptics.sky.engines.core.sky_error` and
  :class:`~dustoptics.sky.engines.core.SkyError`: Delta E 2000 mean and 95th
  percentile over the dome, CIE xy at the zenith and 10 deg above the Sun,
  and the ratio of the dome's luminance.
- :mod:`~dustoptics.sky.engines.report`: the error table of every engine and
  planet set (``dustoptics engines report``).

Adding an engine: a module here that builds its ``EngineModel`` and registers
it, and one import line below.
"""

from __future__ import annotations

from dustoptics.sky.engines import (
    bevy,
    calcmysky,
    celestia,
    core,
    godot,
    openspace,
    threejs,
    unity,
    unreal,
)
from dustoptics.sky.engines.core import (
    ENGINES,
    EngineFit,
    EngineModel,
    Parameter,
    ReferenceSky,
    SkyError,
    fit_engine,
    reference_skies,
    register_engine,
    sky_error,
)

__all__ = [
    "ENGINES",
    "EngineFit",
    "EngineModel",
    "Parameter",
    "ReferenceSky",
    "SkyError",
    "bevy",
    "calcmysky",
    "celestia",
    "core",
    "fit_engine",
    "godot",
    "openspace",
    "reference_skies",
    "register_engine",
    "sky_error",
    "threejs",
    "unity",
    "unreal",
]
