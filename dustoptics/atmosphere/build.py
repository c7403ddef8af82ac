"""Whole atmosphere sets by name, as ``dustoptics build mars|earth`` writes them.

- :func:`build_atmosphere`: the set ``"mars"``, ``"earth"`` or
  ``"earth-kobe2026"`` (:data:`ATMOSPHERES`), its dust computed from a preset
  or a configuration;
- :func:`set_inputs` and :func:`set_provenance`: the set's provenance record,
  ``<name>_provenance.json`` (the inputs that change its numbers, each
  constituent's table provenance and number density, and an input hash),
  which :func:`dustoptics.io.outputs.write_atmosphere_set` writes beside
  CosmoScout VR's files.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from dustoptics._files import read_checked
from dustoptics._validation import check_choice
from dustoptics.atmosphere import gases, sets
from dustoptics.atmosphere.sets import check_earth_aerosol
from dustoptics.models.build import TableBuilder
from dustoptics.table import canonical_json

if TYPE_CHECKING:
    from dustoptics.atmosphere.sets import Atmosphere
    from dustoptics.models.config import BuildConfig

__all__ = [
    "ATMOSPHERES",
    "EARTH_AEROSOL_KEYWORDS",
    "SET_PROVENANCE_SUFFIX",
    "build_atmosphere",
    "set_inputs",
    "set_provenance",
]

#: Names of the whole atmosphere sets (CosmoScout VR's set of files each).
ATMOSPHERES = ("mars", "earth", "earth-kobe2026")

#: Keywords of :func:`build_atmosphere` that set the "earth" set's aerosols
#: (:func:`~dustoptics.atmosphere.sets.earth_atmosphere`'s).
EARTH_AEROSOL_KEYWORDS = (
    "aerosol",
    "aerosol_optical_depth",
    "aerosol_reference_nm",
    "turbidity",
    "aerosol_relative_humidity_percent",
)

#: File of a set's provenance, beside CosmoScout VR's files: ``<name>_provenance.json``.
SET_PROVENANCE_SUFFIX = "_provenance.json"

#: The dust of the "mars" set unless another is given (a preset).
DEFAULT_DUST = "blue-moons"


def build_atmosphere(
    name: str,
    *,
    dust: str | BuildConfig = DEFAULT_DUST,
    optical_depth: float = 0.5,
    reference_wavelength_nm: float = 550.0,
    ozone_csv: str | os.PathLike[str] | None = None,
    wavelength_nm: Sequence[float] | None = None,
    progress: TextIO | None = None,
    **earth_aerosol: Any,
) -> Atmosphere:
    """The atmosphere set ``name``, computed.

    Mars: CO2 molecules (Costa et al. 2021 corrected to Martian conditions)
    and the dust ``dust``, computed at CosmoScout VR's 15 wavelengths with
    angles every 0.1 deg (a superset of the files' 1 deg), its number density
    set by the vertical ``optical_depth`` at ``reference_wavelength_nm``
    (<C_ext> computed there exactly).
    Earth: dry air (Bodhaine et al. 1999, 360 ppm CO2), OPAC's continental
    average aerosol at optical depth 0.1 at 550 nm (or the aerosols
    ``earth_aerosol`` names) and the shipped ozone spectrum (Serdyuchenko et
    al. 2014) in Bruneton's layer on 48 wavelengths 360-830 nm
    (:data:`~dustoptics.atmosphere.sets.EARTH_WAVELENGTHS_NM`, which hold 440,
    550 and 680 nm).  Both sets carry the same atmosphere computed at 440, 550
    and 680 nm (:attr:`~dustoptics.atmosphere.sets.Atmosphere.rgb_optics`), for
    the error of the set's wavelength sampling where engines render.
    "earth-kobe2026": Kobe 2026's air, aerosols and ozone on his three
    wavelengths.

    Parameters
    ----------
    name : str
        One of :data:`ATMOSPHERES`: ``"mars"``, ``"earth"``, ``"earth-kobe2026"``.
    dust : str or BuildConfig, optional
        Mars: the dust, a preset name, the path of a TOML configuration file
        or a configuration (:func:`dustoptics.models.files.load_config`);
        it must compute cross-sections (a Mie model).  Default ``"blue-moons"``.
    optical_depth : float, optional
        Mars: vertical optical depth of the dust at
        ``reference_wavelength_nm``, > 0.  Default 0.5. [-]
    reference_wavelength_nm : float, optional
        Mars: wavelength of ``optical_depth``.  Default 550. [nm]
    ozone_csv : path-like, optional
        Earth: ozone cross-sections replacing the shipped spectrum
        (:func:`dustoptics.atmosphere.gases.read_ozone_csv`).
    wavelength_nm : sequence of float, optional
        Mars and Earth: the wavelengths, replacing CosmoScout VR's 15 for Mars
        (:data:`~dustoptics.atmosphere.sets.COSMOSCOUT_WAVELENGTHS_NM`) and the
        48 for Earth (:data:`~dustoptics.atmosphere.sets.EARTH_WAVELENGTHS_NM`). [nm]
    progress : text stream, optional
        Where the dust's or aerosols' computation reports its progress
        (:class:`~dustoptics.models.build.TableBuilder`); None is silent.
    **earth_aerosol
        Earth: the aerosol keywords of
        :func:`~dustoptics.atmosphere.sets.earth_atmosphere` (:data:`EARTH_AEROSOL_KEYWORDS`:
        ``aerosol``, ``aerosol_optical_depth``, ``aerosol_reference_nm``,
        ``turbidity``, ``aerosol_relative_humidity_percent``), checked before
        any work.

    Returns
    -------
    Atmosphere

    Raises
    ------
    ValueError
        An unknown set or dust preset, a dust without cross-sections, or
        ``wavelength_nm`` for "earth-kobe2026".
    """
    check_choice("name", name, ATMOSPHERES)
    _check_earth_aerosol(name, earth_aerosol)
    if wavelength_nm is not None:
        grid_nm = wavelength_nm
    else:
        grid_nm = sets.EARTH_WAVELENGTHS_NM if name == "earth" else sets.COSMOSCOUT_WAVELENGTHS_NM
    if name == "earth-kobe2026":
        if wavelength_nm is not None:
            raise ValueError(
                "wavelength_nm must be None for 'earth-kobe2026' (Kobe's three wavelengths); "
                f"got {wavelength_nm!r}"
            )
        return sets.earth_atmosphere_kobe2026()
    if name == "earth":
        ozone = "serdyuchenko2014" if ozone_csv is None else gases.read_ozone_csv(ozone_csv)
        report = None if progress is None else (lambda line: print(line, file=progress))
        if report is not None:
            report("aerosols: OPAC's components by Mie (once per process)")
        atm = sets.earth_atmosphere(wavelength_nm=grid_nm, ozone=ozone, **earth_aerosol)
        rgb = sets.earth_atmosphere(
            wavelength_nm=sets.RGB_WAVELENGTHS_NM, ozone=ozone, **earth_aerosol
        )
        return replace(atm, rgb_optics=rgb)
    cfg = TableBuilder.from_name(dust, progress=progress).config if isinstance(dust, str) else dust
    if not cfg.phase.uses_mie:
        label = dust if isinstance(dust, str) else cfg.name
        raise ValueError(
            f"dust {label!r} has no cross-sections (a phase-function-only model); "
            "choose a Mie preset"
        )
    grid = replace(
        cfg,
        optics=replace(cfg.optics, wavelengths_nm=tuple(float(w) for w in grid_nm), n_theta=1801),
    )
    dust_table = TableBuilder(grid, progress=progress).build()
    reference = replace(
        cfg, optics=replace(cfg.optics, wavelengths_nm=(float(reference_wavelength_nm),), n_theta=2)
    )
    cext = TableBuilder(reference).build().quantity("cext_um2")
    assert cext is not None  # a Mie configuration computes cross-sections
    rgb_cfg = replace(
        cfg,
        optics=replace(cfg.optics, wavelengths_nm=tuple(sets.RGB_WAVELENGTHS_NM), n_theta=181),
    )
    rgb = sets.mars_atmosphere(
        dust_table=TableBuilder(rgb_cfg).build(),
        optical_depth=optical_depth,
        reference_wavelength_nm=reference_wavelength_nm,
        reference_cext_um2=float(cext[0]),
    )
    atm = sets.mars_atmosphere(
        dust_table=dust_table,
        optical_depth=optical_depth,
        reference_wavelength_nm=reference_wavelength_nm,
        reference_cext_um2=float(cext[0]),
    )
    return replace(atm, rgb_optics=rgb)


def _check_earth_aerosol(name: str, earth_aerosol: Mapping[str, Any]) -> None:
    """The aerosol keywords: known, for "earth" only, and in range (before any work)."""
    unknown = sorted(set(earth_aerosol) - set(EARTH_AEROSOL_KEYWORDS))
    if unknown:
        raise TypeError(
            f"unexpected keyword {', '.join(unknown)}; the aerosol keywords are "
            f"{', '.join(EARTH_AEROSOL_KEYWORDS)}"
        )
    if earth_aerosol and name != "earth":
        raise ValueError(
            f"{', '.join(sorted(earth_aerosol))} set the aerosols of the 'earth' set only; got "
            f"name={name!r}"
        )
    check_earth_aerosol(**earth_aerosol)


def set_inputs(
    name: str,
    *,
    dust: str = DEFAULT_DUST,
    optical_depth: float = 0.5,
    reference_wavelength_nm: float = 550.0,
    ozone_csv: str | os.PathLike[str] | None = None,
    wavelength_nm: Sequence[float] | None = None,
    **earth_aerosol: Any,
) -> dict[str, Any]:
    """The inputs of :func:`build_atmosphere` that change a set's numbers, for its record.

    Parameters
    ----------
    name : str
        The set (:data:`ATMOSPHERES`).
    dust : str, optional
        Mars: the dust's preset name or configuration path, as given.
    optical_depth : float, optional
        Mars: the dust's vertical optical depth. [-]
    reference_wavelength_nm : float, optional
        Mars: the wavelength of ``optical_depth``. [nm]
    ozone_csv : path-like, optional
        Earth: the ozone file given, recorded with the SHA-256 of its bytes.
    wavelength_nm : sequence of float, optional
        The wavelengths given, if any. [nm]
    **earth_aerosol
        Earth: the aerosol keywords given (:data:`EARTH_AEROSOL_KEYWORDS`).

    Returns
    -------
    dict
        ``{"set": name, ...}``, JSON-serializable: the Mars dust, its optical
        depth and reference wavelength; the Earth ozone file and aerosols
        (their name and vertical optical depth at their reference
        wavelength); the wavelengths.
    """
    inputs: dict[str, Any] = {"set": name}
    if wavelength_nm is not None:
        inputs["wavelengths_nm"] = [float(w) for w in wavelength_nm]
    if name == "mars":
        inputs.update(
            dust=dust,
            optical_depth=optical_depth,
            reference_wavelength_nm=reference_wavelength_nm,
        )
    if name == "earth":
        _check_earth_aerosol(name, earth_aerosol)
        aerosol, tau = check_earth_aerosol(**earth_aerosol)
        inputs["aerosol"] = {
            "name": aerosol,
            "optical_depth": tau,
            "reference_wavelength_nm": float(earth_aerosol.get("aerosol_reference_nm", 550.0)),
            "relative_humidity_percent": earth_aerosol.get("aerosol_relative_humidity_percent", 80),
            **({"turbidity": earth_aerosol["turbidity"]} if "turbidity" in earth_aerosol else {}),
        }
    if name != "mars" and ozone_csv is not None:
        data = read_checked(ozone_csv)  # bounded: never a FIFO, a device or a huge file
        inputs["ozone_csv"] = {
            "path": str(Path(ozone_csv)),
            "sha256": hashlib.sha256(data).hexdigest(),
        }
    return inputs


def set_provenance(atmosphere: Atmosphere, inputs: Mapping[str, Any]) -> str:
    """The provenance record of a set, as the JSON text of ``<name>_provenance.json``.

    Parameters
    ----------
    atmosphere : Atmosphere
    inputs : mapping
        What made it (:func:`set_inputs`).

    Returns
    -------
    str
        JSON (sorted keys, a final newline): the inputs, each constituent's
        table name, number density [m^-3] and provenance, and an input hash
        (SHA-256) over the inputs, the constituents' input hashes and their
        number densities.
    """
    constituents: dict[str, dict[str, Any]] = {
        c.role: {
            "table": c.table.name,
            "number_density_per_m3": c.table.quantity("number_density_per_m3"),
            "provenance": c.table.provenance.to_dict(),
        }
        for c in atmosphere.constituents
    }
    hashed = {
        **inputs,
        "constituents": {role: c["provenance"]["input_hash"] for role, c in constituents.items()},
        "number_densities_per_m3": {
            role: c["number_density_per_m3"] for role, c in constituents.items()
        },
    }
    record = {
        "format": "dustoptics atmosphere set provenance",
        "set": atmosphere.name,
        "inputs": hashed,
        "input_hash": hashlib.sha256(canonical_json(hashed).encode("utf-8")).hexdigest(),
        "constituents": constituents,
    }
    return json.dumps(record, indent=2, sort_keys=True, allow_nan=False) + "\n"
