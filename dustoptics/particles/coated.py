"""Coated spheres: a core inside a concentric shell of another material.

Mars climate models describe water-ice clouds nucleated on dust as dust cores
in ice shells (e.g. Madeleine et al. 2012).  :class:`CoatedSphere` names the
two materials and where the interface lies; :func:`dustoptics.compute_optics`
takes it in place of a refractive index and averages coated spheres over the
size distribution of their outer radius, with the interface at a fixed
fraction of it.  The single-sphere solution is
:func:`dustoptics.scattering.mie.coated_sphere`.

References
----------
.. [1] C. F. Bohren and D. R. Huffman, *Absorption and Scattering of Light by
   Small Particles*, Wiley, 1983, chapter 8.
.. [2] O. B. Toon and T. P. Ackerman, "Algorithms for the calculation of
   scattering by stratified spheres," Appl. Opt. 20, 3657-3660 (1981).
   doi:10.1364/AO.20.003657
.. [3] J.-B. Madeleine, F. Forget, E. Millour, T. Navarro and A. Spiga, "The
   influence of radiatively active water ice clouds on the Martian climate,"
   Geophys. Res. Lett. 39, L23202 (2012). doi:10.1029/2012GL053564
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from dustoptics._validation import check_real

__all__ = ["CoatedSphere"]


@dataclass(frozen=True, kw_only=True)
class CoatedSphere:
    """A sphere with a core of one material in a shell of another.

    Give the interface as ``core_radius_fraction`` (r_core / r) or
    ``core_volume_fraction`` ((r_core / r)^3), exactly one, each in [0, 1]:
    0 is a homogeneous sphere of the shell's material, 1 of the core's.

    Parameters
    ----------
    core, shell : complex, str, material or callable
        Refractive indices m = n + i k of core and shell, anything
        :func:`dustoptics.scattering.optics.resolve_refractive_index` accepts
        (a constant, a catalogue name, a material or mixture, a callable). [-]
    core_radius_fraction : float, optional
        Core radius over the sphere's radius, in [0, 1]. [-]
    core_volume_fraction : float, optional
        Core volume over the sphere's volume, in [0, 1]. [-]

    Examples
    --------
    >>> CoatedSphere(core=1.5 + 0.01j, shell=1.31, core_volume_fraction=0.125).core_radius_fraction
    0.5
    """

    core: Any
    shell: Any
    core_radius_fraction: float | None = None
    core_volume_fraction: float | None = None

    def __post_init__(self) -> None:
        if (self.core_radius_fraction is None) == (self.core_volume_fraction is None):
            raise ValueError(
                "give exactly one of core_radius_fraction and core_volume_fraction (each in [0, 1])"
            )
        if self.core_radius_fraction is not None:
            f = check_real("core_radius_fraction", self.core_radius_fraction)
            name, value = "core_radius_fraction", f
        else:
            v = check_real("core_volume_fraction", self.core_volume_fraction)
            name, value = "core_volume_fraction", v
            f = v ** (1.0 / 3.0) if v >= 0.0 else v
        if not 0.0 <= value <= 1.0:
            raise ValueError(
                f"{name} must be in [0, 1] (a core inside the sphere: the shell cannot be thicker "
                f"than the particle, nor the core larger); got {value!r}"
            )
        object.__setattr__(self, "core_radius_fraction", float(f))

    @property
    def radius_fraction(self) -> float:
        """r_core / r. [-]"""
        assert self.core_radius_fraction is not None
        return self.core_radius_fraction

    @property
    def volume_fraction(self) -> float:
        """(r_core / r)^3. [-]"""
        return self.radius_fraction**3

    def describe(self, core_label: str, shell_label: str) -> str:
        """One line for provenance."""
        return (
            f"coated sphere: core {core_label}, shell {shell_label}, "
            f"core radius fraction {self.radius_fraction:.6g} (volume {self.volume_fraction:.6g})"
        )

    def __repr__(self) -> str:
        return (
            f"CoatedSphere(core={self.core!r}, shell={self.shell!r}, "
            f"core_radius_fraction={self.radius_fraction!r})"
        )
