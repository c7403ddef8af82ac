"""The NASA Ames Mars GCM's dust files (formats ``ames-dustvis``, ``ames-dustir``).

``<name>_Dust_<vis|ir>_15bands.dat`` (and its ``.json`` sidecar): per radius, Q_ext, Q_sca
and g averaged over each of the model's 7 visible bands (0.24-4.5 um, Planck-weighted at
6000 K) or 8 infrared bands (4.5-1000 um, at 215 K), in the layout of its
``Dust_vis_wolff2010_JD_15bands.dat`` and ``Dust_ir_wolff2010_JD_15bands.dat``.

Read from the model's public repository, nasa/AmesGCM at commit
eaba9b5400031651f6d5545acbca08eaf471defb (:data:`AMES_COMMIT`),
``atmos_param_mars/Rad/rtmod_mgcm.F90``:

- the files are headerless: for each of ``nbin_rt = 20`` radii, three lines, Q_ext, Q_sca
  and g, each with one value per band, read by
  ``read(62,'(7(e10.3,2x))') (qextv_dst(i,l), l=1,nlonv)`` (visible, 7 bands) and
  ``read(63,'(8(e10.3,2x))') (qexti_dst(i,l), l=1,nloni)`` (infrared, 8 bands in the
  15-band set-up);
- the radii are ``rad_rt``: 1e-7 m to 50e-6 m, each ``vrat_rt**(1/3)`` times the one
  before (log-spaced); the model weights the rows with its own log-normal distribution
  (``dev_dt = 0.63676``, v_eff = 0.5) by the cross-section in each radius bin
  (``opt_dst``, ``calc_opts``), so a row is the efficiency of particles of that radius:
  :data:`SINGLE_RADII` is the default here (``--gcm-v-eff`` gives distributions instead);
- the bands, in increasing wavenumber: visible edges ``bwnv`` (2222.22 to 41666.67 cm^-1,
  0.24-4.5 um, ``setspv``), infrared ``bwni`` (10 to 2222.222 cm^-1, 4.5-1000 um,
  ``setspi`` for ``ames_15band``);
- the band weighting: the source says of its Wolff dust values "M. Wolff
  Planck-weighted values (T=6000K)" for the visible and "(T=215K)" for the infrared
  (``setrad``); the files' own weighting is not stated anywhere in the repository, so
  these are the defaults here: <Q> = int Q B_nu(T) dnu / int B_nu(T) dnu over the band,
  <g> weighted by Q_sca B_nu.

Each ``.dat`` file has a JSON sidecar (same stem, ``.json``) saying what it was made of,
since the layout has no room for a header.
"""

from __future__ import annotations

import functools
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.io._atomic import FormatError, safe_stem, write_files
from dustoptics.io.gcm.common import (
    GcmOptions,
    check_radii,
    gcm_particles,
    grid_optics,
    planck_band_average,
    planck_bands,
)
from dustoptics.io.registry import Format, option, register

__all__ = [
    "AMES_COMMIT",
    "BANDS",
    "DEFAULT_RADII_UM",
    "IR_RECORD",
    "SINGLE_RADII",
    "VIS_RECORD",
    "AmesBands",
    "AmesFile",
    "AmesOptions",
    "ames_grid",
    "ames_text",
    "describe_ames",
    "is_ames",
    "read_ames",
    "write_ames",
]

#: The nasa/AmesGCM commit the layout, bands and radii were read from.
AMES_COMMIT = "eaba9b5400031651f6d5545acbca08eaf471defb"

#: ``rad_rt``: 20 radii, 0.1-50 um, log-spaced (``ames_radsetup``). [um]
DEFAULT_RADII_UM = tuple(float(r) for r in np.geomspace(0.1, 50.0, 20))

#: The default rows are single radii (the model applies its own size distribution).
SINGLE_RADII = True

#: Gauss-Legendre nodes in wavenumber per band, by default.  A single sphere's efficiencies
#: ripple with wavelength: over the 20 radii of the visible file, 16 -> 64 nodes changes
#: the band means by up to 2 %, 64 -> 128 by 0.46 %, 128 -> 256 by 0.08 % (Q) and 2e-4
#: (g) (``scripts/ames_reproduction.py --nodes-per-band N``).
DEFAULT_NODES_PER_BAND = 128

#: The width of a field of the model's read format ``e10.3``.
_FIELD = 10


@dataclass(frozen=True)
class AmesBands:
    """One of the model's two spectral sets.

    Attributes
    ----------
    key : str
        ``"vis"`` or ``"ir"``.
    title : str
    edges_cm : tuple of float
        Band edges, increasing wavenumber (``bwnv``, ``bwni``). [cm^-1]
    temperature_k : float
        Default Planck temperature of the band means. [K]
    file_name : str
        The name the model opens (``rtdata_path`` + this).
    """

    key: str
    title: str
    edges_cm: tuple[float, ...]
    temperature_k: float
    file_name: str


BANDS = {
    "vis": AmesBands(
        "vis",
        "visible",
        (2222.22, 3087.37, 4030.63, 5370.57, 7651.11, 12500.00, 25000.00, 41666.67),
        6000.0,
        "Dust_vis_wolff2010_JD_15bands.dat",
    ),
    "ir": AmesBands(
        "ir",
        "infrared",
        (10.000, 300.300, 549.451, 636.943, 704.225, 775.194, 970.874, 1282.051, 2222.222),
        215.0,
        "Dust_ir_wolff2010_JD_15bands.dat",
    ),
}


@dataclass(frozen=True)
class AmesOptions(GcmOptions):
    """The Ames files' options: radius grid, v_eff, band weighting and its nodes."""

    gcm_temperature_k: float | None = option(
        help="Ames files: Planck temperature of the band means in K (default 6000 visible, "
        "215 infrared, as the model's source states for its Wolff dust values)",
        type="positive_float",
        metavar="T",
    )
    gcm_nodes_per_band: int | None = option(
        help=f"Ames files: Gauss-Legendre nodes in wavenumber per band (default "
        f"{DEFAULT_NODES_PER_BAND})",
        type="positive_int",
        metavar="N",
    )


def ames_grid(
    table: Any,
    *,
    bands: str,
    gcm_radii_um: tuple[float, ...] | None = None,
    gcm_v_eff: float | None = None,
    gcm_temperature_k: float | None = None,
    gcm_nodes_per_band: int | None = None,
) -> dict[str, Any]:
    """The band means of one spectral set over the radius grid.

    Returns
    -------
    dict
        ``radius_um``, ``qext``, ``qsca``, ``g`` (shape (n_radius, n_band)), ``bands``
        (:class:`~dustoptics.io.gcm.common.Bands`), ``temperature_k``, ``nodes_per_band``,
        ``particles`` and ``optics`` (the :class:`~dustoptics.io.gcm.common.GridOptics` at
        the nodes).
    """
    spec = BANDS[bands]
    radii = check_radii(gcm_radii_um)
    radii = np.asarray(DEFAULT_RADII_UM) if radii is None else radii
    particles = gcm_particles(table, format_name=f"ames-dust{bands}")
    temperature = spec.temperature_k if gcm_temperature_k is None else float(gcm_temperature_k)
    nodes = DEFAULT_NODES_PER_BAND if gcm_nodes_per_band is None else int(gcm_nodes_per_band)
    b = planck_bands(
        spec.edges_cm,
        temperature_k=temperature,
        nodes_per_band=nodes,
        wavelength_range_nm=particles.wavelength_range_nm,
    )
    optics = grid_optics(
        particles,
        radius_um=radii,
        wavelength_nm=b.wavelength_nm,
        v_eff=gcm_v_eff,
        single=SINGLE_RADII,
    )
    qext, qsca, g = planck_band_average(optics, b)
    return {
        "radius_um": radii,
        "qext": qext,
        "qsca": qsca,
        "g": g,
        "bands": b,
        "temperature_k": temperature,
        "nodes_per_band": nodes,
        "particles": particles,
        "optics": optics,
    }


def _line(values: np.ndarray) -> str:
    fields = [f"{v:{_FIELD}.3E}" for v in values]
    if any(len(f) != _FIELD for f in fields):
        raise ValueError(f"a value does not fit the model's e10.3 field: {values.tolist()!r}")
    return "  ".join(fields)


def ames_text(grid: dict[str, Any]) -> str:
    """The headerless text: per radius a Q_ext, a Q_sca and a g line."""
    lines = []
    for i in range(grid["radius_um"].size):
        lines += [_line(grid["qext"][i]), _line(grid["qsca"][i]), _line(grid["g"][i])]
    return "\n".join(lines) + "\n"


def _sidecar(grid: dict[str, Any], bands: str, v_eff: float | None) -> str:
    spec, b, p = BANDS[bands], grid["bands"], grid["particles"]
    record = {
        "format": f"ames-dust{bands}",
        "layout": f"nasa/AmesGCM {AMES_COMMIT}, atmos_param_mars/Rad/rtmod_mgcm.F90: per radius "
        "a Q_ext, a Q_sca and a g line, one e10.3 value per band",
        "model_file_name": spec.file_name,
        "table": p.name,
        "input_hash": p.input_hash,
        "radius_um": [float(r) for r in grid["radius_um"]],
        "rows": "single radii"
        if v_eff is None
        else f"effective radii, v_eff = {v_eff:g} ({p.distribution['model']} family or "
        "modified_gamma)",
        "band_edges_cm-1": list(spec.edges_cm),
        "averaged_cm-1": [
            [float(lo), float(hi)] for lo, hi in zip(b.lower_cm, b.upper_cm, strict=True)
        ],
        "planck_energy_covered": [round(float(c), 6) for c in b.covered],
        "planck_temperature_k": grid["temperature_k"],
        "nodes_per_band": grid["nodes_per_band"],
        "efficiencies": "per mean geometric cross-section, Mie theory for spheres; g weighted "
        "by Q_sca B_nu",
    }
    return json.dumps(record, indent=1, sort_keys=True) + "\n"


def write_ames(
    table: Any,
    out_dir: str | os.PathLike[str],
    *,
    bands: str,
    overwrite: bool = False,
    **keywords: Any,
) -> list[Path]:
    """Write ``<name>_Dust_<bands>_15bands.dat`` and its ``.json`` sidecar atomically.

    Parameters
    ----------
    table : Table
        A table built from a configuration with a material and size distribution.
    out_dir : path
    bands : {"vis", "ir"}
    overwrite : bool
    **keywords
        :class:`AmesOptions` fields.
    """
    grid = ames_grid(table, bands=bands, **keywords)
    stem = Path(out_dir) / f"{safe_stem(table.name)}_Dust_{bands}_15bands"
    return write_files(
        {
            stem.with_suffix(".dat"): ames_text(grid).encode("ascii"),
            stem.with_suffix(".json"): _sidecar(grid, bands, keywords.get("gcm_v_eff")).encode(
                "ascii"
            ),
        },
        overwrite=overwrite,
    )


@dataclass(frozen=True)
class AmesFile:
    """An Ames dust file read back: Q_ext, Q_sca and g, each shape (n_radius, n_band)."""

    qext: np.ndarray
    qsca: np.ndarray
    g: np.ndarray


def read_ames(path: str | os.PathLike[str], *, n_bands: int) -> AmesFile:
    """Read a file in the Ames layout (``n_bands`` fields of 10 characters and 2 spaces).

    Raises
    ------
    FormatError
        A line that does not hold ``n_bands`` numbers, or a count of lines not a multiple of 3.
    """
    p = Path(path)
    rows = []
    for number, line in enumerate(p.read_text(encoding="ascii").splitlines(), start=1):
        cells = [line[i * (_FIELD + 2) : i * (_FIELD + 2) + _FIELD] for i in range(n_bands)]
        try:
            rows.append([float(c) for c in cells])
        except ValueError:
            raise FormatError(f"{p}, line {number}: not {n_bands} e10.3 fields: {line!r}") from None
    if not rows or len(rows) % 3:
        raise FormatError(f"{p}: {len(rows)} lines; expected three per radius")
    a = np.array(rows).reshape(-1, 3, n_bands)
    return AmesFile(qext=a[:, 0], qsca=a[:, 1], g=a[:, 2])


def is_ames(path: Path, bands: str) -> bool:
    """A ``<name>_Dust_<bands>_15bands.dat`` file whose first line reads in the layout, or its
    JSON sidecar."""
    stem = f"_Dust_{bands}_15bands"
    if not path.name.endswith((stem + ".dat", stem + ".json")) or not path.is_file():
        return False
    with open(path, encoding="ascii", errors="replace") as f:
        first = f.readline().rstrip("\n")
    if path.suffix == ".json":
        return first == "{"
    return len(first) == len(BANDS[bands].edges_cm[1:]) * (_FIELD + 2) - 2


def describe_ames(path: Path, full: bool = True) -> str:
    """What an Ames dust file holds, for ``dustoptics info`` (with its sidecar, if there; given
    the sidecar, what the file beside it holds)."""
    path = path.with_suffix(".dat")
    bands = "vis" if path.name.endswith("_Dust_vis_15bands.dat") else "ir"
    spec = BANDS[bands]
    f = read_ames(path, n_bands=len(spec.edges_cm) - 1)
    lines = [
        f"NASA Ames Mars GCM dust file ({spec.title}): {path.name}",
        f"radii:           {f.qext.shape[0]} (the model reads 20, nbin_rt)",
        f"bands:           {f.qext.shape[1]}, {spec.edges_cm[0]:g}-{spec.edges_cm[-1]:g} cm^-1",
        f"Q_ext:           {f.qext.min():.4g}-{f.qext.max():.4g}",
        f"Q_sca / Q_ext:   {(f.qsca / f.qext).min():.4g}-{(f.qsca / f.qext).max():.4g}",
        f"g:               {f.g.min():.4g}-{f.g.max():.4g}",
    ]
    sidecar = path.with_suffix(".json")
    if sidecar.is_file():
        record = json.loads(sidecar.read_text(encoding="ascii"))
        lines.insert(1, f"  table {record['table']}, input hash {record['input_hash']}")
        if full:
            lines += [
                f"  rows: {record['rows']}; Planck weighting at {record['planck_temperature_k']:g} K",
                f"  Planck energy of each band inside the refractive index's range: "
                f"{', '.join(f'{c:.4f}' for c in record['planck_energy_covered'])}",
                f"  the model reads it as {record['model_file_name']} (rtdata_path)",
            ]
    return "\n".join(lines)


def _record(spec: AmesBands) -> Format:
    """The format of one spectral set's file."""
    return Format(
        name=f"ames-dust{spec.key}",
        summary=f"NAME_Dust_{spec.key}_15bands.dat: NASA Ames Mars GCM {spec.title} dust file "
        "(Q_ext, Q_sca, g per band and radius) and a JSON sidecar",
        write=functools.partial(write_ames, bands=spec.key),
        suffixes=(".dat", ".json"),
        options=AmesOptions,
        recognise=lambda path: is_ames(path, spec.key),
        describe=describe_ames,
    )


# In the order the formats were listed before (infrared first).
IR_RECORD = register(_record(BANDS["ir"]))
VIS_RECORD = register(_record(BANDS["vis"]))
