"""The Mars dust whose sky is at the centre of the rovers' colour range, by retrieval (issue 30).

Starts from Wolff et al. (2009)'s dust (their CRISM index ``marsdust-wolff2009``
and sizes, modified gamma r_eff 1.5 um, v_eff 0.3) and fits its effective
radius (``r_eff_um``; the index and v_eff stay Wolff et al.'s: two observed
coordinates that move together constrain one size well, not two) with :func:`dustoptics.retrieve.retrieve` so that the
sky's chromaticity seen as the rovers saw it (away from the Sun, 30 degree
above the horizon) is the centre of Bell, Savransky & Wolff (2006)'s range,
x 0.402 +- 0.006, y 0.380 +- 0.003 (the half-widths as one sigma: a fit
within one sigma of the centre is inside the range), with the Sun 30 degree
high, the dust optical depth 0.5 at 550 nm and the ground albedo 0.2 (the
rover comparison's, :func:`dustoptics.sky.compare.mer_chromaticity`).

It writes the observations (``mer_sky.nc``) and the start (``mer-start.toml``)
to ``--work-dir``, runs the same fit as

    dustoptics retrieve mer_sky.nc --model mer-start.toml --fit r_eff_um=0.5:4 --allow-large

prints it, and with ``--write`` writes the preset
``dustoptics/models/data/presets/mer-sky-fit.toml`` (its header: the start and
its citation, the fitted values with their standard errors, the observation,
this command) and ``docs/examples/mer_retrieval.json`` (the fit's path and
both dusts' chromaticity against Sun elevation), which the gallery example
plots.  About 5-15 minutes on one busy core.

    python scripts/mer_retrieval.py --write
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
PRESET = ROOT / "dustoptics" / "models" / "data" / "presets" / "mer-sky-fit.toml"
PATH_JSON = ROOT / "docs" / "examples" / "mer_retrieval.json"
COMMAND = "python scripts/mer_retrieval.py --write"

SUN_ELEVATION_DEG = 30.0
OPTICAL_DEPTH = 0.5
GROUND_ALBEDO = 0.2
BOUNDS = {"r_eff_um": (0.5, 4.0)}
#: Sun elevations of the chromaticity curves the example plots. [deg]
CURVE_ELEVATIONS_DEG = (5.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0)

WOLFF = (
    "M. J. Wolff, M. D. Smith, R. T. Clancy, R. Arvidson, M. Kahre, F. Seelos IV, S. Murchie "
    'and H. Savijarvi, "Wavelength dependence of dust aerosol single scattering albedo as '
    'observed by the Compact Reconnaissance Imaging Spectrometer," J. Geophys. Res., vol. 114, '
    "E00D04, 2009, doi:10.1029/2009JE003350"
)
BELL = (
    'J. F. Bell III, D. Savransky and M. J. Wolff, "Chromaticity of the Martian sky as observed '
    'by the Mars Exploration Rover Pancam instruments," J. Geophys. Res., vol. 111, no. E12, '
    "2006, doi:10.1029/2006JE002687"
)


def config_text(
    name: str, description: str, r_eff_um: float, v_eff: float, header: str = ""
) -> str:
    """A Mie dust configuration: Wolff et al.'s index, modified gamma sizes."""
    return (
        header
        + f'name = "{name}"\n'
        + f'description = "{description}"\n\n'
        + "choices = [\n"
        + "    \"weighting = 'scattering': the physical single-scattering phase function\",\n"
        + '    "default grids: 48 wavelengths 360..830 nm step 10, 1,801 angles step 0.1 deg",\n'
        + "]\n\n"
        + "[[sources]]\n"
        + 'name = "wolff2009"\n'
        + 'role = "dust refractive index (CRISM retrieval); the starting sizes"\n'
        + f"citation = {json.dumps(WOLFF)}\n\n"
        + "[[sources]]\n"
        + 'name = "bell2006"\n'
        + 'role = "the rovers\' sky chromaticity range the sizes are fitted to"\n'
        + f"citation = {json.dumps(BELL)}\n\n"
        + "[material]\n"
        + 'model = "mars_dust"\n'
        + "hematite_fraction = 0.0           # no hematite added: Wolff et al.'s index alone [-]\n"
        + 'host_index = "marsdust-wolff2009"\n\n'
        + "[size_distribution]\n"
        + 'model = "modified_gamma"\n'
        + f"r_eff_um = {r_eff_um!r}             # [um]\n"
        + f"v_eff = {v_eff!r}                   # [-]\n\n"
        + "[optics]\n"
        + 'weighting = "scattering"\n'
        + "rtol = 1e-4                       # [-]\n"
        + "wavelengths_nm = { start = 360, stop = 830, step = 10 }   # [nm]\n"
        + "n_theta = 1801\n\n"
        + "[phase]\n"
        + 'model = "mie"\n'
    )


def observations() -> Any:
    """The centre of the rovers' range as a sky_chromaticity observation."""
    import xarray as xr

    from dustoptics.sky.compare import MER_SKY_CHROMATICITY

    centre = [float(np.mean(MER_SKY_CHROMATICITY[c])) for c in ("x", "y")]
    half = [float(np.diff(MER_SKY_CHROMATICITY[c])[0] / 2) for c in ("x", "y")]
    return xr.Dataset(
        {
            "sky_chromaticity": (
                ("sun_elevation_deg", "chromaticity"),
                [centre],
                {
                    "optical_depth": OPTICAL_DEPTH,
                    "ground_albedo": GROUND_ALBEDO,
                    "long_name": "centre of the MER sky chromaticity range (Bell et al. 2006)",
                },
            ),
            "sky_chromaticity_uncertainty": (("sun_elevation_deg", "chromaticity"), [half]),
        },
        coords={"sun_elevation_deg": [SUN_ELEVATION_DEG], "chromaticity": ["x", "y"]},
    )


def curve(model: dict, elevations: tuple[float, ...]) -> list[list[float]]:
    """(x, y) of ``model``'s sky at each Sun elevation (the fit's sky settings)."""
    import xarray as xr

    from dustoptics.retrieve.sky import SkyModel, SkySettings, sky_progress, sky_samples
    from dustoptics.scattering.optics import compute_optics

    var = xr.DataArray(
        np.zeros((len(elevations), 2)),
        dims=("sun_elevation_deg", "chromaticity"),
        coords={"sun_elevation_deg": list(elevations), "chromaticity": ["x", "y"]},
        name="sky_chromaticity",
        attrs={"optical_depth": OPTICAL_DEPTH, "ground_albedo": GROUND_ALBEDO},
    )
    sky = SkyModel(sky_samples(var, np.ones(var.shape)), SkySettings())
    table = compute_optics(**model, wavelength_nm=sky.wavelength_nm)
    return sky.values(table, sky_progress(sys.stderr)).reshape(-1, 2).tolist()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--write", action="store_true", help=f"write {PRESET.name} and {PATH_JSON.name}")
    p.add_argument("--work-dir", type=Path, help="where the observations and the start go")
    args = p.parse_args(argv)

    from dustoptics.models.config import parse_config
    from dustoptics.retrieve import retrieve
    from dustoptics.retrieve.fit import _model_keywords

    work = args.work_dir or Path(tempfile.mkdtemp(prefix="mer-retrieval-"))
    work.mkdir(parents=True, exist_ok=True)
    obs = observations()
    obs.to_netcdf(work / "mer_sky.nc", engine="h5netcdf")
    start_text = config_text(
        "mer-start", "Wolff et al. 2009's Mars dust (index and sizes)", 1.5, 0.3
    )
    (work / "mer-start.toml").write_text(start_text, encoding="utf-8")
    start = parse_config(start_text, source="mer-start.toml")
    fit = retrieve(
        obs,
        model=start,
        parameters=list(BOUNDS),
        bounds=BOUNDS,
        max_iterations=20,
        progress=sys.stderr,
        allow_large=True,
    )
    x, y = (obs["sky_chromaticity"].values[0] + fit.residuals * np.array([0.006, 0.003])).tolist()
    print(f"{'converged' if fit.converged else 'NOT converged'}: {fit.message}")
    for p_, v, se in zip(fit.parameters, fit.values, fit.standard_errors):
        print(f"  {p_} = {v:.4f} +- {se:.4f}")
    print(f"  sky x {x:.4f}, y {y:.4f}; chi-square {fit.chi_square:.3g}; {fit.sky_solves} skies")
    if not args.write:
        return 0
    r_eff, v_eff = round(fit.value("r_eff_um"), 4), 0.3
    se = dict(zip(fit.parameters, fit.standard_errors.tolist()))
    header = (
        "# mer-sky-fit: Wolff et al. (2009)'s Mars dust, its effective radius fitted to the "
        "rovers' sky colour.\n#\n"
        "# What it is\n"
        "#   Wolff et al. 2009's dust refractive index (CRISM, catalogue marsdust-wolff2009),\n"
        "#   no hematite added, modified gamma sizes with Wolff et al.'s v_eff 0.3 and the\n"
        "#   effective radius fitted by dustoptics.retrieve so that\n"
        "#   the sky's CIE 1931 chromaticity seen as the rovers saw it (away from the Sun,\n"
        "#   30 degree above the horizon) is the centre of the MER range of Bell, Savransky\n"
        "#   & Wolff (2006), x 0.396-0.408, y 0.377-0.383, taken as x 0.402 +- 0.006,\n"
        "#   y 0.380 +- 0.003 (half-widths as one sigma), with the Sun 30 degree high, dust\n"
        "#   optical depth 0.5 at 550 nm, ground albedo 0.2 (the rover comparison's,\n"
        "#   dustoptics.sky.compare.mer_chromaticity), 20 streams.\n"
        "#   Start: Wolff et al. 2009's r_eff 1.5 um (v_eff 0.3 held).\n"
        f"#   Fitted: r_eff_um = {fit.value('r_eff_um'):.4f} +- {se['r_eff_um']:.4f} um, the sky\n"
        f"#   at x {x:.4f}, y {y:.4f} (chi-square {fit.chi_square:.3f} of 2 coordinates);\n"
        f"#   {fit.function_evaluations} evaluations, {fit.sky_solves} sky solves.  The standard\n"
        "#   error says how far r_eff may move before the sky leaves one sigma (the range's\n"
        "#   half-width) of the centre.\n"
        "#   Rounded to 4 decimals below.  At other Sun elevations the sky is redder (lower\n"
        "#   Sun) or bluer (higher): the gallery example plot_mer_retrieval plots it.\n"
        "#   Reproduce (writes this file):\n"
        f"#     {COMMAND}\n"
        "#   or on the command line, with the observation file and start the script writes:\n"
        "#     dustoptics retrieve mer_sky.nc --model mer-start.toml --fit r_eff_um=0.5:4 \\\n"
        "#         --allow-large\n"
        "#   Licence: the numbers are dustoptics's (MIT licence); the index is Wolff et\n"
        "#   al.'s (see the catalogue entry marsdust-wolff2009).\n\n"
    )
    text = config_text(
        "mer-sky-fit",
        f"Wolff et al. 2009 Mars dust, r_eff fitted to the MER sky colour "
        f"(r_eff {r_eff} um, v_eff {v_eff})",
        r_eff,
        v_eff,
        header,
    )
    PRESET.write_text(text, encoding="utf-8")
    fitted = parse_config(text, source=PRESET.name)
    record = {
        "written_by": COMMAND,
        "parameters": list(fit.parameters),
        "values": fit.values.tolist(),
        "standard_errors": fit.standard_errors.tolist(),
        "covariance": fit.covariance.tolist(),
        "observation": obs["sky_chromaticity"].values[0].tolist(),
        "uncertainty": [0.006, 0.003],
        "sun_elevation_deg": SUN_ELEVATION_DEG,
        "optical_depth": OPTICAL_DEPTH,
        "ground_albedo": GROUND_ALBEDO,
        "path_values": fit.history_values.tolist(),
        "path_xy": (
            obs["sky_chromaticity"].values[0] + fit.history_residuals * np.array([0.006, 0.003])
        ).tolist(),
        "curve_sun_elevation_deg": list(CURVE_ELEVATIONS_DEG),
        "curve_start_xy": curve(_model_keywords(start), CURVE_ELEVATIONS_DEG),
        "curve_fitted_xy": curve(_model_keywords(fitted), CURVE_ELEVATIONS_DEG),
    }
    PATH_JSON.write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {PRESET} and {PATH_JSON}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
