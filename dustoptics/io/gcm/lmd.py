"""The LMD Mars PCM's dust optical-property files (formats ``lmd-dustvis``, ``lmd-dustir``).

``<name>_optprop_dust<vis|ir>_n<nsize>.dat``: Q_ext, single-scattering albedo and g per
wavelength and effective radius, over the PCM's visible (0.1-5 um) or infrared (5-200 um)
bands, in the layout of the PCM's ``optprop_dustvis_TM_n50.dat`` and ``optprop_dustir_n50.dat``.

The layout is the one the PCM's ``suaer.F90`` reads (LMD Mars PCM, ``phymars/suaer.F90``;
read from a public copy of the source, see :doc:`/howto/gcm_dust_files`): lines whose
first list-directed item starts with ``#`` are comments; then, each read list-directed
from a new line, ``nwvl``, ``nsize``, the wavelength axis ``wvl(nwvl)`` [m], the radius
axis ``radiusdyn(nsize)`` [m], and per radius ``ep(:,isize)`` (Q_ext), then per radius
``omeg(:,isize)`` (single-scattering albedo), then per radius ``gfactor(:,isize)`` (g).
The PCM averages them itself over its bands (``aerave``: Planck at 6000 K over
0.1-0.5-5 um in the visible, at 215 K over 5-200 um in the infrared, from
``dimradmars_mod.F90``) and normalizes Q_ext by its value at the reference wavelength
(0.67 um visible, ``longrefvis``; 9.3 um infrared in the ``dustrefir`` default), so the
wavelength axis must bracket the reference wavelength.  Between the axis's points
``aerave`` interpolates linearly in wavelength, and beyond its ends it holds the end
values (read from a public copy of ``aerave.F``).

The radius axis is a grid of effective radii: the PCM's own files carry 50, log-spaced
from 1e-3 to 10 um (the list public converters reproduce: ``Wetewe/Build_Dust``,
``Other files/LMD-GCM 50 reffs.txt``, commit 538d04ff7927da9a92e0088b9ec775ff00d13291),
the default here; the PCM allows up to ``nsizemax = 60``.

Each file starts with :data:`FIRST_LINE` and says in comments what it was made from; the
numbers are printed with 7 significant digits, five to a line.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dustoptics.io._atomic import FormatError, safe_stem, write_files
from dustoptics.io._text import printable
from dustoptics.io.gcm.common import (
    GcmOptions,
    check_radii,
    gcm_particles,
    grid_optics,
    scalable_radii,
)
from dustoptics.io.registry import Format, option, register

__all__ = [
    "DEFAULT_RADII_UM",
    "DOMAINS",
    "FIRST_LINE",
    "IR_RECORD",
    "VIS_RECORD",
    "LmdDomain",
    "LmdFile",
    "LmdOptions",
    "describe_lmd",
    "is_lmd",
    "lmd_text",
    "read_lmd",
    "write_lmd",
]

#: The first line of every file written here (the domain follows it).
FIRST_LINE = "# dustoptics: LMD Mars PCM dust optical properties,"

#: The PCM's radius grid: 50 effective radii, log-spaced over 1e-3-10 um. [um]
DEFAULT_RADII_UM = tuple(float(r) for r in np.geomspace(1e-3, 10.0, 50))

#: Most radii the PCM takes (``nsizemax`` in ``dimradmars_mod.F90``).
NSIZEMAX = 60

#: Values per data line.
_PER_LINE = 5


@dataclass(frozen=True)
class LmdDomain:
    """One of the PCM's two radiation domains.

    Attributes
    ----------
    key : str
        ``"vis"`` or ``"ir"`` (the file name's ``optprop_dust<key>``).
    title : str
        For the header.
    band_um : tuple of float
        The PCM's band limits for the domain (``long1vis``, ``long3vis``; ``long1ir``,
        ``long2ir``). [um]
    reference_um : float
        The reference wavelength (``longrefvis``; ``longrefir``). [um]
    temperature_k : float
        The Planck temperature of the PCM's band averages (``tsun``; ``tsol``). [K]
    """

    key: str
    title: str
    band_um: tuple[float, float]
    reference_um: float
    temperature_k: float


DOMAINS = {
    "vis": LmdDomain("vis", "visible", (0.1, 5.0), 0.67, 6000.0),
    "ir": LmdDomain("ir", "infrared", (5.0, 200.0), 9.3, 215.0),
}

#: Wavelengths of the default axis, log-spaced over the domain's bands (within the index).
_N_WAVELENGTHS = 40


@dataclass(frozen=True)
class LmdOptions(GcmOptions):
    """The LMD files' options: the radius grid, v_eff and the wavelength axis."""

    gcm_wavelengths_um: tuple[float, ...] | None = option(
        help="LMD files: wavelength axis in um, comma-separated, bracketing the reference "
        "wavelength (default: 40 log-spaced over the PCM's bands within the refractive "
        "index's range, plus the reference wavelength)",
        type="floats",
        metavar="W[,W...]",
    )

    def check(self, wavelength_nm: Any) -> None:
        """Refuse, before the table is computed, what the writer would refuse."""
        super().check(wavelength_nm)
        _check_size(check_radii(self.gcm_radii_um))
        if self.gcm_wavelengths_um is not None:
            _checked_wavelengths(self.gcm_wavelengths_um)


def _check_size(radii: np.ndarray | None) -> None:
    if radii is not None and radii.size > NSIZEMAX:
        raise ValueError(
            f"gcm_radii_um has {radii.size} radii; the PCM takes at most {NSIZEMAX} (nsizemax)"
        )


def _checked_wavelengths(given: tuple[float, ...]) -> np.ndarray:
    w = np.asarray(given, dtype=np.float64)
    if w.size < 2 or np.any(np.diff(w) <= 0) or not np.all(np.isfinite(w)) or w[0] <= 0:
        raise ValueError(
            f"gcm_wavelengths_um must be two or more increasing wavelengths > 0 [um]; got {list(given)!r}"
        )
    return w


def _wavelength_axis(
    domain: LmdDomain, given: tuple[float, ...] | None, index_range_nm: tuple[float, float]
) -> np.ndarray:
    """The wavelength axis [um]: given (checked) or the default."""
    low, high = index_range_nm[0] / 1e3, index_range_nm[1] / 1e3
    if given is None:
        lo, hi = max(domain.band_um[0], low), min(domain.band_um[1], high)
        if not lo <= domain.reference_um <= hi:
            raise ValueError(
                f"the refractive index ({low:g}-{high:g} um) does not reach the PCM's "
                f"{domain.title} reference wavelength {domain.reference_um:g} um"
            )
        axis = np.union1d(np.geomspace(lo, hi, _N_WAVELENGTHS), [domain.reference_um])
        return axis
    w = _checked_wavelengths(given)
    if not w[0] <= domain.reference_um <= w[-1]:
        raise ValueError(
            f"gcm_wavelengths_um ({w[0]:g}-{w[-1]:g} um) must bracket the PCM's {domain.title} "
            f"reference wavelength {domain.reference_um:g} um"
        )
    return w


def _rows(values: np.ndarray) -> list[str]:
    """Five values a line, 7 significant digits, each line starting with the number."""
    flat = [f"{v:.6E}" for v in np.asarray(values, dtype=np.float64).ravel()]
    return [" ".join(flat[i : i + _PER_LINE]) for i in range(0, len(flat), _PER_LINE)]


def lmd_text(
    table: Any,
    *,
    domain: str,
    gcm_radii_um: tuple[float, ...] | None = None,
    gcm_v_eff: float | None = None,
    gcm_wavelengths_um: tuple[float, ...] | None = None,
) -> tuple[str, np.ndarray, Any]:
    """The file's text for one domain, its radius axis [um] and its :class:`GridOptics`."""
    d = DOMAINS[domain]
    name = f"lmd-dust{domain}"
    radii = check_radii(gcm_radii_um)
    _check_size(radii)
    particles = gcm_particles(table, format_name=name)
    left_out = ""
    if radii is None:
        default = np.asarray(DEFAULT_RADII_UM)
        radii = scalable_radii(particles.distribution, default, v_eff=gcm_v_eff)
        if radii.size < default.size:
            left_out = (
                f" ({default.size - radii.size} of the PCM's {default.size} radii, below "
                f"{radii[0]:.4g} um, left out: the build's fine mode would be below 1 nm)"
            )
    axis_um = _wavelength_axis(d, gcm_wavelengths_um, particles.wavelength_range_nm)
    optics = grid_optics(particles, radius_um=radii, wavelength_nm=axis_um * 1e3, v_eff=gcm_v_eff)
    shape = (
        f"the build's size distribution ({particles.distribution['model']}) scaled to each r_eff"
        if gcm_v_eff is None
        else f"r_eff and v_eff = {gcm_v_eff:g}"
    )
    lines = [
        f"{FIRST_LINE} {d.title}",
        f"# table {printable(particles.name)}, input hash {particles.input_hash}",
        "# layout of the PCM's suaer.F90; wavelengths and radii in metres",
        f"# radius axis: effective radii; distributions: {shape}{left_out}",
        "# Q_ext per mean geometric cross-section; Mie theory for spheres; g and albedo "
        "cross-section weighted",
        f"# PCM reference wavelength of the domain: {d.reference_um:g} um; "
        f"its bands span {d.band_um[0]:g}-{d.band_um[1]:g} um, this axis "
        f"{axis_um[0]:g}-{axis_um[-1]:g} um",
        "# Number of wavelengths (nwvl):",
        str(axis_um.size),
        "# Number of radius (nsize):",
        str(radii.size),
        "# Wavelength axis (wvl):",
        *_rows(axis_um * 1e-6),
        "# Particle size axis (radius):",
        *_rows(radii * 1e-6),
    ]
    for title, values in (
        ("Extinction coef. Qext (ep)", optics.qext),
        ("Single Scat Albedo (omeg)", optics.ssa),
        ("Assymetry Factor (gfactor)", optics.g),
    ):
        lines.append(f"# {title}:")
        for i in range(radii.size):
            lines += [f"# Radius number {i + 1}", *_rows(values[i])]
    return "\n".join(lines) + "\n", radii, optics


def write_lmd(
    table: Any,
    out_dir: str | os.PathLike[str],
    *,
    domain: str,
    overwrite: bool = False,
    **keywords: Any,
) -> list[Path]:
    """Write ``<name>_optprop_dust<domain>_n<nsize>.dat`` atomically.

    Parameters
    ----------
    table : Table
        A table built from a configuration with a material and size distribution.
    out_dir : path
    domain : {"vis", "ir"}
    overwrite : bool
    **keywords
        :class:`LmdOptions` fields.

    Returns
    -------
    list of Path
    """
    text, radii, _ = lmd_text(table, domain=domain, **keywords)
    path = Path(out_dir) / f"{safe_stem(table.name)}_optprop_dust{domain}_n{radii.size}.dat"
    return write_files({path: text.encode("ascii")}, overwrite=overwrite)


@dataclass(frozen=True)
class LmdFile:
    """An LMD dust file read back (SI units as in the file).

    Attributes
    ----------
    wavelength_m : numpy.ndarray, shape (nwvl,)
    radius_m : numpy.ndarray, shape (nsize,)
    qext, ssa, g : numpy.ndarray, shape (nsize, nwvl)
    header : tuple of str
        The comment lines before the first number.
    """

    wavelength_m: np.ndarray
    radius_m: np.ndarray
    qext: np.ndarray
    ssa: np.ndarray
    g: np.ndarray
    header: tuple[str, ...]


def read_lmd(path: str | os.PathLike[str]) -> LmdFile:
    """Read an LMD dust file as the PCM does: comments skipped, numbers in sequence.

    Raises
    ------
    FormatError
        Missing or extra numbers, or counts that are not positive integers.
    """
    p = Path(path)
    header: list[str] = []
    tokens: list[str] = []
    for line in p.read_text(encoding="ascii").splitlines():
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            if not tokens and stripped:
                header.append(stripped)
            continue
        tokens += stripped.replace(",", " ").split()
    try:
        nwvl, nsize = int(tokens[0]), int(tokens[1])
        values = np.array([float(t) for t in tokens[2:]])
    except (IndexError, ValueError) as err:
        raise FormatError(f"{p}: not an LMD dust file ({err})") from None
    expected = nwvl + nsize + 3 * nwvl * nsize
    if nwvl < 1 or nsize < 1 or values.size != expected:
        raise FormatError(
            f"{p}: {values.size} numbers after nwvl = {nwvl} and nsize = {nsize}; expected {expected}"
        )
    blocks = values[nwvl + nsize :].reshape(3, nsize, nwvl)
    return LmdFile(
        wavelength_m=values[:nwvl],
        radius_m=values[nwvl : nwvl + nsize],
        qext=blocks[0],
        ssa=blocks[1],
        g=blocks[2],
        header=tuple(header),
    )


def is_lmd(path: Path) -> bool:
    """A ``.dat`` file whose first line starts with :data:`FIRST_LINE`."""
    if path.suffix != ".dat" or not path.is_file():
        return False
    with open(path, encoding="ascii", errors="replace") as f:
        return f.readline().startswith(FIRST_LINE)


def describe_lmd(path: Path, full: bool = True) -> str:
    """What an LMD dust file holds, for ``dustoptics info``."""
    f = read_lmd(path)
    domain = f.header[0][len(FIRST_LINE) :].strip()
    lines = [
        f"LMD Mars PCM dust file ({domain}): {path.name}",
        f"  {f.header[1][2:]}",
        f"wavelengths:     {f.wavelength_m.size}, {f.wavelength_m[0] * 1e6:g}-"
        f"{f.wavelength_m[-1] * 1e6:g} um",
        f"radii:           {f.radius_m.size} effective radii, {f.radius_m[0] * 1e6:g}-"
        f"{f.radius_m[-1] * 1e6:g} um",
        f"Q_ext:           {f.qext.min():.4g}-{f.qext.max():.4g}",
        f"albedo:          {f.ssa.min():.4g}-{f.ssa.max():.4g}",
        f"g:               {f.g.min():.4g}-{f.g.max():.4g}",
    ]
    if full:
        lines += [f"  {h[2:]}" for h in f.header[2:] if not h.startswith("# Number")]
        model_name = (
            "optprop_dustir_n50.dat" if domain == "infrared" else "optprop_dustvis_TM_n50.dat"
        )
        lines.append(
            f"  the PCM reads it as {model_name} in its datadir (or the name set in suaer.F90's "
            "file_id)"
        )
    return "\n".join(lines)


def _record(domain: LmdDomain) -> Format:
    """The format of one domain's file."""
    return Format(
        name=f"lmd-dust{domain.key}",
        summary=f"NAME_optprop_dust{domain.key}_nN.dat: LMD Mars PCM {domain.title} dust file "
        "(Q_ext, albedo, g per wavelength and radius)",
        write=functools.partial(write_lmd, domain=domain.key),
        suffixes=(".dat",),
        options=LmdOptions,
        recognise=lambda path: is_lmd(path) and f"_optprop_dust{domain.key}_" in path.name,
        describe=describe_lmd,
    )


# In the order the formats were listed before (infrared first).
IR_RECORD = register(_record(DOMAINS["ir"]))
VIS_RECORD = register(_record(DOMAINS["vis"]))
