"""Write the reference values the tests compare against into ``tests/data/``.

The tests carry their reference data inside the repository.  Each file under ``tests/data/`` is
written by this script: a header that gives the publication (citation), the licence, where the
numbers were read (provenance) and what was selected, then only the rows and columns the tests
use.  The numbers themselves are not changed (the text of every selected cell is copied as
printed, so the tests' "half a unit of the last printed digit" tolerances stay those of the
source), except where a file says it holds bin means computed here.

The numbers were transcribed from their sources (named in each header) into a folder of
reference material kept beside the repository by the project's maintainers; this script reads
that folder, which users of the repository do not need:

    python scripts/make_test_data.py --source ../shared [--out tests/data]

Run it only to add or change reference data; the files it writes are committed.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: The licence sentence for numbers whose source states none.
NO_LICENCE = (
    "none stated by the source for these numbers; they are published reference values, "
    "quoted here with their citation to verify the computation"
)
#: What the project claims for the file itself.
THIS_FILE = "header and selection: MIT, as dustoptics"


@dataclass(frozen=True)
class Reference:
    """One file of tests/data: where it comes from and what of it the tests use."""

    source: str  # path below the source folder
    target: str  # path below tests/data
    title: str
    citation: str
    licence: str
    selection: str
    rows: Callable[[dict[str, str]], bool] | None = None
    columns: tuple[str, ...] | None = None


MIEV0 = (
    "W. J. Wiscombe, Improved Mie scattering algorithms, Appl. Opt. 19, 1505-1509 (1980), "
    "doi:10.1364/AO.19.001505; the MIEV0 test driver MVTstNew.f (BLOCK DATA CHEKMI)"
)
WISCOMBE1979 = (
    "W. J. Wiscombe, Mie scattering calculations: advances in technique and fast, vector-speed "
    "computer codes, NCAR Tech. Note NCAR/TN-140+STR (1979), doi:10.5065/D6ZP4414, Appendix"
)
QUERRY = "M. R. Querry, Optical constants, Contractor Report CRDC-CR-85034 (1985)"
CC0 = "CC0 1.0 (refractiveindex.info database, public domain dedication)"
BRUNETON_BSD = "BSD-3-Clause (E. Bruneton's code, from which the numbers were read)"

REFERENCES = (
    Reference(
        "reference-data/mie-benchmarks/miev0_wiscombe_efficiencies.csv",
        "mie-benchmarks/miev0_wiscombe_efficiencies.csv",
        "MIEV0 test cases: efficiencies Qext, Qsca and g*Qsca of single spheres",
        MIEV0,
        NO_LICENCE,
        "the 15 cases of finite refractive index (cases 1-4, perfect conductors, left out)",
        rows=lambda r: r["perfect_conductor"] == "0",
    ),
    Reference(
        "reference-data/mie-benchmarks/miev0_wiscombe_amplitudes.csv",
        "mie-benchmarks/miev0_wiscombe_amplitudes.csv",
        "MIEV0 test cases: complex amplitudes S1, S2 at 0, 30, ..., 180 degree",
        MIEV0,
        NO_LICENCE,
        "the 15 cases of finite refractive index (m_re > 0)",
        rows=lambda r: float(r["m_re"]) > 0,
    ),
    Reference(
        "reference-data/mie-benchmarks/miev0_wiscombe_legendre_moments.csv",
        "mie-benchmarks/miev0_wiscombe_legendre_moments.csv",
        "MIEV0 test cases: normalized Legendre moments of the polarized phase quantities",
        MIEV0,
        NO_LICENCE,
        "cases 9 and 10 (IPOLZN = 1234), the ones the tests compute",
        rows=lambda r: r["case"] in ("9", "10"),
    ),
    Reference(
        "reference-data/mie-benchmarks/wiscombe1979_ncar_efficiencies.csv",
        "mie-benchmarks/wiscombe1979_ncar_efficiencies.csv",
        "Wiscombe (1979) test cases: Qext, Qabs, Qsca and g for m = 1.5 and 1.5 +/- 0.1i",
        WISCOMBE1979,
        NO_LICENCE,
        "all 8 cases",
    ),
    Reference(
        "reference-data/mie-benchmarks/wiscombe1979_ncar_angular.csv",
        "mie-benchmarks/wiscombe1979_ncar_angular.csv",
        "Wiscombe (1979) test cases: S11 at 0, 5, ..., 180 degree",
        WISCOMBE1979,
        NO_LICENCE,
        "all 8 cases; the column S11 (the degree of polarization left out)",
        columns=("case", "x", "n", "k", "theta_deg", "S11"),
    ),
    Reference(
        "reference-data/refractive-index/ri_hematite_querry1985_extraordinary.csv",
        "refractive-index/ri_hematite_querry1985_extraordinary.csv",
        "Hematite (alpha-Fe2O3), extraordinary ray: n and k",
        QUERRY,
        CC0,
        "every row, in source order (the tests check how defects of the source are handled)",
    ),
    Reference(
        "reference-data/refractive-index/ri_hematite_querry1985_ordinary.csv",
        "refractive-index/ri_hematite_querry1985_ordinary.csv",
        "Hematite (alpha-Fe2O3), ordinary ray: n and k",
        QUERRY,
        CC0,
        "every row, in source order (the tests check how defects of the source are handled)",
    ),
    Reference(
        "reference-data/refractive-index/ri_magnetite_querry1985.csv",
        "refractive-index/ri_magnetite_querry1985.csv",
        "Magnetite (Fe3O4): n and k",
        QUERRY,
        CC0,
        "every row, in source order (the tests check how defects of the source are handled)",
    ),
    Reference(
        "reference-data/refractive-index/ri_marsdust_wolff2009_ranjan.csv",
        "refractive-index/ri_marsdust_wolff2009_ranjan.csv",
        "Mars dust, retrieved effective refractive index: n and k",
        "M. J. Wolff et al., Wavelength dependence of dust aerosol single scattering albedo as "
        "observed by the Compact Reconnaissance Imaging Spectrometer, J. Geophys. Res. 114, "
        "E00D04 (2009), doi:10.1029/2009JE003350; table distributed by the NASA Ames Mars "
        "Climate Modeling Group",
        NO_LICENCE,
        "the first and last rows (the table's range) and the rows at 0.5 and 0.7 um",
        rows=lambda r: r["wavelength_um"] in ("0.263000", "0.500000", "0.700000", "98.5423"),
    ),
    Reference(
        "reference-data/refractive-index/ri_co2_bideaumehu1973_coefficients.csv",
        "refractive-index/ri_co2_bideaumehu1973_coefficients.csv",
        "CO2 gas: dispersion-formula coefficients",
        "A. Bideau-Mehu, Y. Guern, R. Abjean and A. Johannin-Gilles, Interferometric "
        "determination of the refractive index of carbon dioxide in the ultraviolet region, "
        "Opt. Commun. 9, 432-434 (1973)",
        CC0,
        "every coefficient",
    ),
    Reference(
        "reference-data/refractive-index/ri_air_ciddor1996_coefficients.csv",
        "refractive-index/ri_air_ciddor1996_coefficients.csv",
        "Standard dry air: dispersion-formula coefficients",
        "P. E. Ciddor, Refractive index of air: new equations for the visible and near "
        "infrared, Appl. Opt. 35, 1566-1573 (1996)",
        CC0,
        "every coefficient",
    ),
    Reference(
        "reference-data/refractive-index/ri_air_peckreeder1972_coefficients.csv",
        "refractive-index/ri_air_peckreeder1972_coefficients.csv",
        "Standard dry air: dispersion-formula coefficients",
        "E. R. Peck and K. Reeder, Dispersion of air, J. Opt. Soc. Am. 62, 958-962 (1972)",
        CC0,
        "every coefficient",
    ),
    Reference(
        "reference-data/spectra/cie1931_2deg_cmf_bruneton_5nm.csv",
        "spectra/cie1931_2deg_cmf_bruneton_5nm.csv",
        "CIE 1931 2-degree colour-matching functions, 360-830 nm every 5 nm",
        "CIE 015:2004 Colorimetry (CIE 1931 standard observer); CVRL tabulation ciexyz31.txt",
        BRUNETON_BSD + "; the CIE's tabulated values are freely distributed by the CIE and CVRL",
        "every row",
    ),
    Reference(
        "reference-data/spectra/solar_irradiance_bruneton_pas_astmg173.csv",
        "spectra/solar_irradiance_bruneton_pas_astmg173.csv",
        "Extraterrestrial solar spectral irradiance, ASTM G173-03, means over 10 nm bins",
        "ASTM G173-03, Standard Tables for Reference Solar Spectral Irradiances (ETR column)",
        BRUNETON_BSD,
        "every row",
    ),
    Reference(
        "reference-data/spectra/xyz_to_linear_srgb_bruneton.csv",
        "spectra/xyz_to_linear_srgb_bruneton.csv",
        "CIE XYZ to linear sRGB matrix (rows)",
        "IEC 61966-2-1:1999, Multimedia systems and equipment - Colour measurement and "
        "management - Default RGB colour space - sRGB",
        BRUNETON_BSD,
        "the 3 x 3 matrix",
    ),
    Reference(
        "reference-data/spectra/ozone_xsec_bruneton_pas_233K.csv",
        "spectra/ozone_xsec_bruneton_pas_233K.csv",
        "Ozone absorption cross-section at 233 K, means over 10 nm bins",
        "A. Serdyuchenko, V. Gorshelev, M. Weber, W. Chehade and J. P. Burrows, High spectral "
        "resolution ozone absorption cross-sections - Part 2: Temperature dependence, Atmos. "
        "Meas. Tech. 7, 625-636 (2014), doi:10.5194/amt-7-625-2014",
        BRUNETON_BSD,
        "every row",
    ),
    Reference(
        "reference-data/spectra/rayleigh_penndorf1957_bruneton_clearsky.csv",
        "spectra/rayleigh_penndorf1957_bruneton_clearsky.csv",
        "Rayleigh scattering coefficient of standard air at 0 C, 1013.25 hPa",
        "R. Penndorf, Tables of the refractive index for standard air and the Rayleigh "
        "scattering coefficient for the spectral region between 0.2 and 20.0 um and their "
        "application to atmospheric optics, J. Opt. Soc. Am. 47, 176-182 (1957), Table III",
        BRUNETON_BSD,
        "every row (360-830 nm every 10 nm)",
    ),
    Reference(
        "reference-data/spectra/rayleigh_vardavas_params_photochem.csv",
        "spectra/rayleigh_vardavas_params_photochem.csv",
        "Rayleigh parameters (Vardavas & Carver form): depolarization and refractivity",
        "I. M. Vardavas and J. H. Carver, Solar and terrestrial parameterizations for "
        "radiative-convective models, Planet. Space Sci. 32, 1307-1325 (1984); values per "
        "species from the works cited in the column citations",
        NO_LICENCE,
        "every row",
    ),
)

SEED_CITATION = (
    "T. Meyran, Physically Based Real-Time Rendering of the Martian Atmosphere, master's "
    "thesis, Hochschule Hannover (2022): its published table MiePhaseFunctionSpectrum.csv"
)
#: Every SEED_STEP-th of the seed table's 1,800 angles, and the last one (180 degree).
SEED_STEP = 10
#: Serdyuchenko's 293 K samples are averaged over [L, L + 10) nm for these L.
OZONE_BINS_NM = np.arange(500.0, 700.0, 10.0)


def _header(ref_title: str, citation: str, licence: str, provenance: str, selection: str) -> str:
    lines = [
        f"dustoptics test reference data: {ref_title}.",
        f"Citation: {citation}.",
        f"Licence: {licence}; {THIS_FILE}.",
        f"Provenance: {provenance}",
        f"Selection: {selection}; written by scripts/make_test_data.py.",
    ]
    return "".join(f"# {line}\n" for line in lines)


def _split(path: Path) -> tuple[list[str], list[str]]:
    text = path.read_text(encoding="utf-8").splitlines()
    return [ln for ln in text if ln.startswith("#")], [ln for ln in text if not ln.startswith("#")]


def _provenance(source: str, notes: list[str], how: str = "unchanged") -> str:
    return (
        f"the numbers of {source} in the maintainers' reference folder (not shipped), "
        f"{how}.  Its notes (the files read, with repository and commit; units, sign "
        "conventions, defects of the source):\n"
        + "".join(f"# {ln[1:].strip()}\n" for ln in notes if ln[1:].strip())
    ).rstrip("\n")


def write_csv(ref: Reference, source: Path, out: Path) -> Path:
    notes, body = _split(source / ref.source)
    rows = list(csv.DictReader(body))
    fields = list(ref.columns or csv.DictReader(body).fieldnames or [])
    chosen = [r for r in rows if ref.rows is None or ref.rows(r)]
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(fields)
    writer.writerows([r[f] for f in fields] for r in chosen)
    target = out / ref.target
    target.parent.mkdir(parents=True, exist_ok=True)
    header = _header(
        ref.title, ref.citation, ref.licence, _provenance(ref.source, notes), ref.selection
    )
    target.write_text(header + buffer.getvalue(), encoding="utf-8")
    return target


def write_bohren_huffman(source: Path, out: Path) -> Path:
    """The sample as published, with a key saying what the file is (numbers kept as printed)."""
    text = (source / "reference-data/mie-benchmarks/bohren_huffman_bhmie_sample.json").read_text(
        encoding="utf-8"
    )
    about = {
        "title": "dustoptics test reference data: Bohren & Huffman's BHMIE sample calculation",
        "citation": "C. F. Bohren and D. R. Huffman, Absorption and Scattering of Light by "
        "Small Particles, Wiley (1983), Appendix A, p. 482",
        "licence": f"{NO_LICENCE}; {THIS_FILE}",
        "provenance": "numbers as transcribed from the sources in files_read, unchanged; "
        "written by scripts/make_test_data.py",
    }
    start = text.index("{") + 1
    entry = json.dumps({"dustoptics_reference": about}, indent=1)[1:-1].rstrip() + ","
    target = out / "mie-benchmarks" / "bohren_huffman_bhmie_sample.json"
    target.write_text(text[:start] + entry + text[start:], encoding="utf-8")
    json.loads(target.read_text(encoding="utf-8"))  # still valid
    return target


def write_ozone_bins(source: Path, out: Path) -> Path:
    """Serdyuchenko's raw 293 K samples averaged over 10 nm bins (computed here)."""
    path = source / "reference-data/spectra/ozone_xsec_serdyuchenko2014_293K_raw_355-845nm.csv"
    notes, body = _split(path)
    data = np.array([[float(x) for x in ln.split(",")] for ln in body[1:] if ln])
    lam, sigma_cm2 = data[:, 0], data[:, 1]
    lines = ["bin_start_nm,sigma_O3_cm2,n_samples"]
    for start in OZONE_BINS_NM:
        inside = (lam >= start) & (lam < start + 10.0)
        lines.append(f"{start:.0f},{sigma_cm2[inside].mean():.10g},{int(inside.sum())}")
    ref = next(r for r in REFERENCES if r.target.endswith("ozone_xsec_bruneton_pas_233K.csv"))
    header = _header(
        "Ozone absorption cross-section at 293 K, means over 10 nm bins [L, L + 10) nm",
        ref.citation + "; 293 K, 2013 version of the data",
        NO_LICENCE,
        _provenance(path.relative_to(source).as_posix(), notes, "averaged over bins here"),
        "bins from 500 to 690 nm: each value the mean of the source's samples (0.01 nm grid) "
        "with L <= wavelength < L + 10 nm, computed by this script (n_samples of them)",
    )
    target = out / "spectra" / "ozone_xsec_serdyuchenko2014_293K_binmean_500-700nm.csv"
    target.write_text(header + "\n".join(lines) + "\n", encoding="utf-8")
    return target


def write_seed_excerpt(source: Path, out: Path) -> Path:
    """The seed's Blue Moon's table at every SEED_STEP-th angle, in the seed's own layout."""
    lines = (
        (source / "seed-tables" / "MiePhaseFunctionSpectrum.csv")
        .read_text(encoding="utf-8")
        .splitlines()
    )
    data = lines[1:]
    keep = sorted({*range(0, len(data), SEED_STEP), len(data) - 1})
    header = _header(
        "Blue Moon's Mars-dust phase function spectrum of the seed thesis [sr^-1]",
        SEED_CITATION,
        NO_LICENCE,
        "the thesis's published CSV file (seed-tables/MiePhaseFunctionSpectrum.csv in the "
        "maintainers' reference folder, not shipped), cells copied as printed.  Layout: first header cell "
        "empty, then the wavelengths [nm]; each row an angle theta [degree] (the thesis's "
        "linspace(0, 180, 1800)) and the phase function at each wavelength (normalized to 1 "
        "over the sphere; computed by the thesis with 5,000 random radii per wavelength, so "
        "about 0.5 % Monte-Carlo noise)",
        f"the header line, then every {SEED_STEP}th angle of the 1,800 (row indices 0, "
        f"{SEED_STEP}, ..., and the last, 180 degree): {len(keep)} rows, all 48 wavelengths",
    )
    target = out / "seed-tables" / "MiePhaseFunctionSpectrum_excerpt.csv"
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(
        header + "\n".join([lines[0], *(data[i] for i in keep)]) + "\n", encoding="utf-8"
    )
    return target


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", type=Path, default=ROOT.parent / "shared")
    parser.add_argument("--out", type=Path, default=ROOT / "tests" / "data")
    args = parser.parse_args(argv)
    written = [write_csv(ref, args.source, args.out) for ref in REFERENCES]
    written += [
        write_bohren_huffman(args.source, args.out),
        write_ozone_bins(args.source, args.out),
        write_seed_excerpt(args.source, args.out),
    ]
    for path in written:
        print(f"{path.relative_to(args.out)}: {path.stat().st_size:,} bytes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
