"""Effective refractive index of a mixture of two materials.

Dust grains are not pure minerals: the Mars dust model of Ehlers et al. (2014)
is a few per cent hematite dispersed in a transparent host of index 1.5.  An
effective-medium rule turns the two indices and the inclusions' volume
fraction into one index that Mie theory can use for the grain as a whole.

- :func:`maxwell_garnett`: inclusions isolated in a continuous host
  (Maxwell Garnett 1904); not symmetric in host and inclusion.
- :func:`bruggeman`: both components on an equal footing (Bruggeman 1935).
- :class:`Mixture`: either rule as a material, evaluated per wavelength.
- :func:`mars_dust`: the seed thesis's "Blue Moon's" dust, hematite in n = 1.5.

All functions work with complex refractive indices ``m = n + i k`` (``k >= 0``
absorbs); the rules themselves act on the permittivity ``eps = m**2`` and the
result is returned as ``m = sqrt(eps)`` on the branch with ``k >= 0``.

References
----------
.. [1] J. C. Maxwell Garnett, "Colours in metal glasses and in metallic films",
   Phil. Trans. R. Soc. Lond. A 203, 385-420 (1904), doi:10.1098/rsta.1904.0024.
.. [2] D. A. G. Bruggeman, "Berechnung verschiedener physikalischer Konstanten
   von heterogenen Substanzen. I.", Ann. Phys. 416, 636-664 (1935),
   doi:10.1002/andp.19354160705.
.. [3] V. A. Markel, "Introduction to the Maxwell Garnett approximation:
   tutorial", J. Opt. Soc. Am. A 33, 1244-1256 (2016),
   doi:10.1364/JOSAA.33.001244.
.. [4] K. Ehlers, R. Chakrabarty and H. Moosmüller, "Blue moons and Martian
   sunsets", Appl. Opt. 53, 1808-1819 (2014), doi:10.1364/AO.53.001808.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dustoptics._validation import (
    _show,
    as_float_array,
    check_choice,
    check_closed_interval,
)
from dustoptics.particles.catalogue import as_refractive_index, get_material, list_materials
from dustoptics.particles.materials import (
    ConstantIndex,
    RefractiveIndex,
    _index_from_epsilon,
    _intersect_ranges,
)

__all__ = [
    "MARS_DUST_DENSITY_KG_M3",
    "MIXING_RULES",
    "Mixture",
    "bruggeman",
    "bruggeman_derivatives",
    "mars_dust",
    "maxwell_garnett",
    "maxwell_garnett_derivatives",
]

ComplexArray = NDArray[np.complex128]
FloatArray = NDArray[np.float64]

#: Density of Martian dust grains, 2500 kg m^-3, as used for the dust of the
#: LMD Mars Global Climate Model: J.-B. Madeleine, F. Forget, J. W. Head,
#: B. Levrard, F. Montmessin and E. Millour, "Revisiting the radiative impact
#: of dust on Mars using the LMD Global Climate Model," J. Geophys. Res. 116,
#: E11010 (2011), doi:10.1029/2011JE003855.  Pass it as
#: ``compute_optics(..., particle_density_kg_m3=MARS_DUST_DENSITY_KG_M3)``
#: for mass extinction coefficients. [kg m^-3]
MARS_DUST_DENSITY_KG_M3: Final = 2500.0

#: Names of the mixing rules accepted by :class:`Mixture` and :func:`mars_dust`.
MIXING_RULES: Final = ("maxwell_garnett", "bruggeman")

_RULE_CITATIONS: Final = {
    "maxwell_garnett": (
        "Maxwell Garnett mixing rule: J. C. Maxwell Garnett, Colours in metal glasses and in "
        "metallic films, Phil. Trans. R. Soc. Lond. A 203, 385-420 (1904), doi:10.1098/rsta.1904.0024"
    ),
    "bruggeman": (
        "Bruggeman mixing rule: D. A. G. Bruggeman, Berechnung verschiedener physikalischer "
        "Konstanten von heterogenen Substanzen. I., Ann. Phys. 416, 636-664 (1935), "
        "doi:10.1002/andp.19354160705"
    ),
}

_EHLERS2014: Final = (
    "K. Ehlers, R. Chakrabarty and H. Moosmüller, Blue moons and Martian sunsets, "
    "Appl. Opt. 53, 1808-1819 (2014), doi:10.1364/AO.53.001808"
)
_MEYRAN2022: Final = (
    "T. Meyran, Physically Based Real-Time Rendering of the Martian Atmosphere, "
    "M.Sc. thesis, Hochschule Hannover (2022)"
)

#: Hematite choices of :func:`mars_dust`: short names and the catalogue names they stand for.
MARS_DUST_HEMATITE: Final = {
    "querry-extraordinary": "hematite-querry1985-extraordinary",
    "querry-ordinary": "hematite-querry1985-ordinary",
    "querry-average": "hematite-querry1985-average",
}


# ---------------------------------------------------------------------------
# Input checks
# ---------------------------------------------------------------------------


def _as_index_array(name: str, values: ArrayLike) -> ComplexArray:
    """Complex refractive indices with n > 0, k >= 0, finite, as a new array."""
    try:
        m = np.array(values, dtype=np.complex128)
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be complex refractive indices n + ik; got {_show(values)}"
        ) from None
    bad = ~np.isfinite(m) | (m.real <= 0.0) | (m.imag < 0.0)
    if np.any(bad):
        raise ValueError(
            f"{name} must be finite complex refractive indices n + ik with n > 0 and k >= 0 "
            f"(k >= 0 absorbs); got {_show(m[bad])}"
        )
    return m


def _as_volume_fraction(values: ArrayLike) -> FloatArray:
    """Volume fractions in the closed interval [0, 1], as a new array."""
    v = as_float_array("volume_fraction", values)
    outside = (v < 0.0) | (v > 1.0)
    if np.any(outside):
        raise ValueError(
            f"volume_fraction must be in the closed interval [0, 1]; got {_show(v[outside])}"
        )
    return v


def _broadcast(
    host: ArrayLike, inclusion: ArrayLike, volume_fraction: ArrayLike
) -> tuple[ComplexArray, ComplexArray, FloatArray]:
    m_host = _as_index_array("host", host)
    m_incl = _as_index_array("inclusion", inclusion)
    v = _as_volume_fraction(volume_fraction)
    try:
        m_host, m_incl, v = np.broadcast_arrays(m_host, m_incl, v)
    except ValueError:
        raise ValueError(
            f"host, inclusion and volume_fraction must broadcast together; got shapes "
            f"{m_host.shape}, {m_incl.shape} and {v.shape}"
        ) from None
    return m_host, m_incl, v


def _exact_limits(
    m: ComplexArray, m_host: ComplexArray, m_incl: ComplexArray, v: FloatArray
) -> ComplexArray:
    """Return the host itself at v = 0 and the inclusion itself at v = 1."""
    return np.asarray(
        np.where(v == 0.0, m_host, np.where(v == 1.0, m_incl, m)), dtype=np.complex128
    )


# ---------------------------------------------------------------------------
# Mixing rules
# ---------------------------------------------------------------------------


def maxwell_garnett(
    *, host: ArrayLike, inclusion: ArrayLike, volume_fraction: ArrayLike
) -> ComplexArray:
    """Maxwell Garnett effective index of inclusions dispersed in a host.

    .. math::

        \\varepsilon_\\mathrm{eff} = \\varepsilon_h
        \\frac{\\varepsilon_i + 2\\varepsilon_h + 2 v (\\varepsilon_i - \\varepsilon_h)}
             {\\varepsilon_i + 2\\varepsilon_h - v (\\varepsilon_i - \\varepsilon_h)},
        \\qquad m_\\mathrm{eff} = \\sqrt{\\varepsilon_\\mathrm{eff}},

    with ``eps = m**2`` for host (h) and inclusion (i) and ``v`` the volume
    fraction of the inclusions [1]_, [2]_.  Equivalently the Clausius-Mossotti
    form ``(eps_eff - eps_h)/(eps_eff + 2 eps_h) = v (eps_i - eps_h)/(eps_i + 2 eps_h)``.

    Parameters
    ----------
    host : array_like of complex
        Refractive index of the continuous host, ``n + ik`` with n > 0,
        k >= 0. [dimensionless]
    inclusion : array_like of complex
        Refractive index of the spherical inclusions. [dimensionless]
    volume_fraction : array_like of float
        Volume fraction of the inclusions, in [0, 1]. [dimensionless]

    Returns
    -------
    numpy.ndarray of complex128
        Effective index ``n + ik`` with ``k >= 0``, of the broadcast shape of
        the three inputs (0-d for scalars). [dimensionless]

    Raises
    ------
    ValueError
        If an index has n <= 0, k < 0 or is not finite, a volume fraction is
        outside [0, 1], the shapes do not broadcast, or the denominator
        vanishes (a resonance of metallic inclusions, eps_i = -2 eps_h (2 + v)/(1 - v)).

    Notes
    -----
    The rule assumes small, well-separated spherical inclusions; it is not
    symmetric in host and inclusion, and at large ``v`` it is an
    extrapolation.  The limits are returned exactly: ``v = 0`` gives
    ``host`` and ``v = 1`` gives ``inclusion`` (the formula would give
    ``sqrt(m**2)``, which may differ in the last bit).  To first order in
    ``v``, ``d eps_eff / dv = 3 eps_h (eps_i - eps_h)/(eps_i + 2 eps_h)`` and
    it agrees with :func:`bruggeman`.

    References
    ----------
    .. [1] J. C. Maxwell Garnett, "Colours in metal glasses and in metallic
       films", Phil. Trans. R. Soc. Lond. A 203, 385-420 (1904),
       doi:10.1098/rsta.1904.0024.
    .. [2] V. A. Markel, "Introduction to the Maxwell Garnett approximation:
       tutorial", J. Opt. Soc. Am. A 33, 1244-1256 (2016),
       doi:10.1364/JOSAA.33.001244.

    Examples
    --------
    >>> maxwell_garnett(host=1.5, inclusion=2.927 + 0.46j, volume_fraction=0.03)
    array(1.5336...+0.0071...j)
    """
    m_host, m_incl, v = _broadcast(host, inclusion, volume_fraction)
    eps_h = m_host * m_host
    eps_i = m_incl * m_incl
    contrast = eps_i - eps_h
    numerator = eps_i + 2.0 * eps_h + 2.0 * v * contrast
    denominator = eps_i + 2.0 * eps_h - v * contrast
    if np.any(denominator == 0.0):
        raise ValueError(
            "maxwell_garnett: the denominator eps_i + 2 eps_h - v (eps_i - eps_h) vanishes for "
            f"inclusion {_show(m_incl[denominator == 0.0])} in host {_show(m_host[denominator == 0.0])}"
        )
    m = _index_from_epsilon(eps_h * numerator / denominator)
    return _exact_limits(m, m_host, m_incl, v)


def bruggeman(*, host: ArrayLike, inclusion: ArrayLike, volume_fraction: ArrayLike) -> ComplexArray:
    """Bruggeman (symmetric effective-medium) index of a two-component mixture.

    ``eps_eff`` solves

    .. math::

        v \\frac{\\varepsilon_i - \\varepsilon}{\\varepsilon_i + 2\\varepsilon}
        + (1 - v) \\frac{\\varepsilon_h - \\varepsilon}{\\varepsilon_h + 2\\varepsilon} = 0,

    that is the quadratic ``2 eps**2 - b eps - eps_i eps_h = 0`` with
    ``b = (3v - 1) eps_i + (2 - 3v) eps_h`` [1]_; ``m_eff = sqrt(eps_eff)``.

    Parameters
    ----------
    host : array_like of complex
        Refractive index of the first component (volume fraction ``1 - v``),
        ``n + ik`` with n > 0, k >= 0. [dimensionless]
    inclusion : array_like of complex
        Refractive index of the second component (volume fraction ``v``).
        [dimensionless]
    volume_fraction : array_like of float
        Volume fraction of ``inclusion``, in [0, 1]. [dimensionless]

    Returns
    -------
    numpy.ndarray of complex128
        Effective index ``n + ik`` with ``k >= 0``, of the broadcast shape of
        the inputs (0-d for scalars). [dimensionless]

    Raises
    ------
    ValueError
        As for :func:`maxwell_garnett`.

    Notes
    -----
    Choice of root: of the two roots we return the one with the larger
    imaginary part (a passive medium has ``Im eps >= 0``); when both are real
    (both components lossless) the one with the larger real part, which is
    then the positive one, since the product of the roots is
    ``-eps_i eps_h / 2 < 0``.  At ``v = 0`` the roots are ``eps_h`` and
    ``-eps_i / 2``, so this choice is the host, and it follows the host
    continuously as ``v`` grows to the inclusion at ``v = 1`` (checked in the
    tests for n in [1, 4], k in [0, 3]).  The roots are computed in the
    cancellation-free form ``q = (b + s)/4``, ``eps_i eps_h / (-2 q)`` with
    the sign of ``s = sqrt(b**2 + 8 eps_i eps_h)`` chosen so that
    ``Re(conj(b) s) >= 0``.  The rule is symmetric:
    ``bruggeman(host=a, inclusion=b, volume_fraction=v)`` equals
    ``bruggeman(host=b, inclusion=a, volume_fraction=1 - v)``.  The limits
    ``v = 0`` and ``v = 1`` are returned exactly.

    References
    ----------
    .. [1] D. A. G. Bruggeman, "Berechnung verschiedener physikalischer
       Konstanten von heterogenen Substanzen. I.", Ann. Phys. 416, 636-664
       (1935), doi:10.1002/andp.19354160705.
    """
    m_host, m_incl, v = _broadcast(host, inclusion, volume_fraction)
    eps_h = m_host * m_host
    eps_i = m_incl * m_incl
    b = (3.0 * v - 1.0) * eps_i + (2.0 - 3.0 * v) * eps_h
    s = np.sqrt(b * b + 8.0 * eps_i * eps_h)
    s = np.where((np.conj(b) * s).real >= 0.0, s, -s)
    root_1 = (b + s) / 4.0  # |b + s| >= |b|: no cancellation, and never 0 as eps_i eps_h != 0
    root_2 = -eps_i * eps_h / (2.0 * root_1)
    scale = np.abs(root_1) + np.abs(root_2)
    tie = np.abs(root_1.imag - root_2.imag) <= 1e-12 * scale
    first = np.where(tie, root_1.real >= root_2.real, root_1.imag > root_2.imag)
    m = _index_from_epsilon(np.where(first, root_1, root_2))
    return _exact_limits(m, m_host, m_incl, v)


_RULES: Final[dict[str, Callable[..., ComplexArray]]] = {
    "maxwell_garnett": maxwell_garnett,
    "bruggeman": bruggeman,
}


# ---------------------------------------------------------------------------
# Derivatives of the rules
# ---------------------------------------------------------------------------


def maxwell_garnett_derivatives(
    *, host: ArrayLike, inclusion: ArrayLike, volume_fraction: ArrayLike
) -> tuple[ComplexArray, ComplexArray]:
    """dm_eff/dv and dm_eff/dm_host of :func:`maxwell_garnett`, in closed form.

    With Delta = eps_i - eps_h, N = eps_i + 2 eps_h + 2 v Delta and
    D = eps_i + 2 eps_h - v Delta (eps_eff = eps_h N / D):

    - d eps_eff / dv = eps_h Delta (N + 2 D) / D^2,
    - d eps_eff / d eps_h = N / D + eps_h ((2 - 2 v) D - (2 + v) N) / D^2,

    and dm = d eps / (2 m_eff), d eps_h = 2 m_h dm_h.  m_eff is analytic in
    m_h, so d/dn_h = dm_eff/dm_h and d/dk_h = i dm_eff/dm_h.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray) of complex128
        dm_eff/dv and dm_eff/dm_host, of the inputs' broadcast shape. [-]

    Examples
    --------
    >>> d_v, d_h = maxwell_garnett_derivatives(host=1.5, inclusion=2.0, volume_fraction=0.0)
    >>> round(float(d_v.real), 6)  # 3 eps_h (eps_i - eps_h) / (eps_i + 2 eps_h) / (2 m_h)
    0.463235
    """
    m_host, m_incl, v = _broadcast(host, inclusion, volume_fraction)
    m = maxwell_garnett(host=m_host, inclusion=m_incl, volume_fraction=v)
    eps_h = m_host * m_host
    eps_i = m_incl * m_incl
    delta = eps_i - eps_h
    num = eps_i + 2.0 * eps_h + 2.0 * v * delta
    den = eps_i + 2.0 * eps_h - v * delta
    d_v = eps_h * delta * (num + 2.0 * den) / den**2
    d_eps_h = num / den + eps_h * ((2.0 - 2.0 * v) * den - (2.0 + v) * num) / den**2
    return d_v / (2.0 * m), d_eps_h * 2.0 * m_host / (2.0 * m)


def bruggeman_derivatives(
    *, host: ArrayLike, inclusion: ArrayLike, volume_fraction: ArrayLike
) -> tuple[ComplexArray, ComplexArray]:
    """dm_eff/dv and dm_eff/dm_host of :func:`bruggeman`, by implicit differentiation.

    eps = eps_eff solves f = v F(eps_i) + (1 - v) F(eps_h) = 0 with
    F(a) = (a - eps) / (a + 2 eps); so d eps = -(f_v dv + f_h d eps_h) / f_eps
    with f_v = F(eps_i) - F(eps_h), f_h = (1 - v) 3 eps / (eps_h + 2 eps)^2 and
    f_eps = -3 (v eps_i / (eps_i + 2 eps)^2 + (1 - v) eps_h / (eps_h + 2 eps)^2),
    at the root :func:`bruggeman` chooses; then as for
    :func:`maxwell_garnett_derivatives`.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray) of complex128
        dm_eff/dv and dm_eff/dm_host. [-]
    """
    m_host, m_incl, v = _broadcast(host, inclusion, volume_fraction)
    m = bruggeman(host=m_host, inclusion=m_incl, volume_fraction=v)
    eps = m * m
    eps_h = m_host * m_host
    eps_i = m_incl * m_incl
    f_v = (eps_i - eps) / (eps_i + 2.0 * eps) - (eps_h - eps) / (eps_h + 2.0 * eps)
    f_h = (1.0 - v) * 3.0 * eps / (eps_h + 2.0 * eps) ** 2
    f_eps = -3.0 * (
        v * eps_i / (eps_i + 2.0 * eps) ** 2 + (1.0 - v) * eps_h / (eps_h + 2.0 * eps) ** 2
    )
    return -f_v / f_eps / (2.0 * m), -f_h / f_eps * 2.0 * m_host / (2.0 * m)


_RULE_DERIVATIVES: Final[dict[str, Callable[..., tuple[ComplexArray, ComplexArray]]]] = {
    "maxwell_garnett": maxwell_garnett_derivatives,
    "bruggeman": bruggeman_derivatives,
}

#: Prefix of the names :func:`mars_dust` gives its mixtures (they also answer to
#: ``hematite_fraction``).
_MARS_DUST_PREFIX: Final = "mars-dust-ehlers2014("


# ---------------------------------------------------------------------------
# Mixture as a material
# ---------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Mixture(RefractiveIndex):
    """A two-component effective medium, usable wherever a material is.

    ``m(lambda) = rule(host=host(lambda), inclusion=inclusion(lambda),
    volume_fraction=volume_fraction)`` with ``rule`` one of
    :func:`maxwell_garnett` or :func:`bruggeman`.

    Parameters
    ----------
    host : RefractiveIndex, complex or str
        The host (matrix) material; a number ``n + ik`` becomes a
        :class:`~dustoptics.particles.materials.ConstantIndex` and a string is looked up
        in the catalogue.  After construction it is always a RefractiveIndex.
    inclusion : RefractiveIndex, complex or str
        The inclusion material, as for ``host``.
    volume_fraction : float
        Volume fraction of the inclusions, in [0, 1]. [dimensionless]
    rule : {"maxwell_garnett", "bruggeman"}, optional
        Mixing rule; default ``"maxwell_garnett"``.
    name : str, optional
        Defaults to ``"<rule>(<v> <inclusion> in <host>)"``.
    citation : str, optional
        Defaults to the rule's reference followed by the components' citations.

    Attributes
    ----------
    wavelength_range_nm : tuple of float
        Intersection of the components' ranges. [nm]

    Raises
    ------
    ValueError
        If ``volume_fraction`` is outside [0, 1], ``rule`` is unknown (the
        message lists the valid rules), a constant is not a valid index, or
        the components' ranges do not overlap.

    Examples
    --------
    >>> dust = Mixture(host=1.5, inclusion="querry-extraordinary", volume_fraction=0.03)
    >>> dust(550.0)
    array(1.5336...+0.0071...j)
    """

    host: RefractiveIndex | complex | str
    inclusion: RefractiveIndex | complex | str
    volume_fraction: float
    rule: str = "maxwell_garnett"
    name: str = ""
    citation: str = ""
    wavelength_range_nm: tuple[float, float] = field(init=False)

    def __post_init__(self) -> None:
        host = as_refractive_index(self.host, name="host")
        inclusion = as_refractive_index(self.inclusion, name="inclusion")
        fraction = check_closed_interval("volume_fraction", self.volume_fraction, 0.0, 1.0)
        rule = check_choice("rule", self.rule, MIXING_RULES)
        object.__setattr__(self, "host", host)
        object.__setattr__(self, "inclusion", inclusion)
        object.__setattr__(self, "volume_fraction", fraction)
        object.__setattr__(self, "wavelength_range_nm", _intersect_ranges(host, inclusion))
        if not self.name:
            object.__setattr__(
                self, "name", f"{rule}({fraction:g} {inclusion.name} in {host.name})"
            )
        if not self.citation:
            object.__setattr__(
                self,
                "citation",
                f"{_RULE_CITATIONS[rule]}; host: {host.citation}; inclusion: {inclusion.citation}",
            )

    def _evaluate(self, wavelength_nm: FloatArray) -> ComplexArray:
        host = cast(RefractiveIndex, self.host)
        inclusion = cast(RefractiveIndex, self.inclusion)
        return _RULES[self.rule](
            host=host(wavelength_nm),
            inclusion=inclusion(wavelength_nm),
            volume_fraction=self.volume_fraction,
        )

    # ------------------------------------------------------------ derivatives

    @property
    def index_parameters(self) -> tuple[str, ...]:
        """Parameters the effective index can be differentiated with respect to:
        ``"volume_fraction"`` (for :func:`mars_dust` also ``"hematite_fraction"``),
        ``"host_n"`` and ``"host_k"`` (the host's index shifted by the same
        amount at every wavelength)."""
        names: tuple[str, ...] = ("volume_fraction", "host_n", "host_k")
        if self.name.startswith(_MARS_DUST_PREFIX):
            names = ("hematite_fraction", *names)
        return names

    def index_derivatives(self, wavelength_nm: ArrayLike) -> dict[str, ComplexArray]:
        """dm_eff/dp for every :attr:`index_parameters` p, per wavelength (chain
        rule through :func:`maxwell_garnett_derivatives` or
        :func:`bruggeman_derivatives`). [-] per unit of p

        Examples
        --------
        >>> d = mars_dust().index_derivatives([550.0])
        >>> bool(d["hematite_fraction"][0] == d["volume_fraction"][0]), sorted(d)[:2]
        (True, ['hematite_fraction', 'host_k'])
        """
        wl = np.atleast_1d(np.asarray(wavelength_nm, dtype=np.float64))
        host = cast(RefractiveIndex, self.host)
        inclusion = cast(RefractiveIndex, self.inclusion)
        d_v, d_h = _RULE_DERIVATIVES[self.rule](
            host=host(wl), inclusion=inclusion(wl), volume_fraction=self.volume_fraction
        )
        out = {"volume_fraction": d_v, "host_n": d_h, "host_k": 1j * d_h}
        if "hematite_fraction" in self.index_parameters:
            out["hematite_fraction"] = d_v
        return out

    def parameter_value(self, parameter: str) -> float:
        """The value of one of :attr:`index_parameters` (host n, k: a constant host's)."""
        check_choice("parameter", parameter, self.index_parameters)
        if parameter in ("volume_fraction", "hematite_fraction"):
            return float(self.volume_fraction)
        m = complex(self._constant_host(parameter).value)
        return m.real if parameter == "host_n" else m.imag

    def with_parameter(self, parameter: str, value: float) -> Mixture:
        """A copy with one of :attr:`index_parameters` set to ``value`` (for
        :func:`dustoptics.retrieve.retrieve`); the host's n and k only of a
        constant host."""
        check_choice("parameter", parameter, self.index_parameters)
        host = cast(RefractiveIndex, self.host)
        fraction = self.volume_fraction
        if parameter in ("volume_fraction", "hematite_fraction"):
            fraction = check_closed_interval(parameter, value, 0.0, 1.0)
        else:
            m = complex(self._constant_host(parameter).value)
            m = complex(value, m.imag) if parameter == "host_n" else complex(m.real, value)
            host = ConstantIndex(value=m)
        name = citation = ""
        if self.name.startswith(_MARS_DUST_PREFIX):
            # As mars_dust names it, so that it still answers to hematite_fraction.
            inclusion = cast(RefractiveIndex, self.inclusion)
            name = f"{_MARS_DUST_PREFIX}{fraction:g} {inclusion.name} in {host.name}, {self.rule})"
            citation = self.citation
        return Mixture(
            host=host,
            inclusion=self.inclusion,
            volume_fraction=fraction,
            rule=self.rule,
            name=name,
            citation=citation,
        )

    def _constant_host(self, parameter: str) -> ConstantIndex:
        if not isinstance(self.host, ConstantIndex):
            raise ValueError(
                f"{parameter} is a value only of a constant host index; this mixture's host is "
                f"{getattr(self.host, 'name', self.host)!r}"
            )
        return self.host


def mars_dust(
    *,
    hematite_fraction: float = 0.03,
    host_index: complex | RefractiveIndex | str = 1.5,
    hematite: str = "querry-extraordinary",
    rule: str = "maxwell_garnett",
) -> Mixture:
    """The seed thesis's "Blue Moon's" Mars dust: hematite inclusions in a clear host.

    ``m = maxwell_garnett(host=host_index, inclusion=m_hematite(lambda),
    volume_fraction=hematite_fraction)`` (or Bruggeman), after Ehlers et al.
    [1]_, who mixed 3 % hematite by volume into a non-absorbing substrate of
    index 1.5 + 0i, as Meyran [2]_ did for the seed's phase-function table.

    Parameters
    ----------
    hematite_fraction : float, optional
        Volume fraction of hematite, in [0, 1]; default 0.03. [dimensionless]
    host_index : complex, RefractiveIndex or str, optional
        Index of the host (may be complex, k >= 0), a material, or a catalogue
        name such as ``"marsdust-wolff2009"`` (the dust index retrieved by
        Wolff et al. 2009, which already contains the dust's own absorbers;
        with ``hematite_fraction=0`` it is returned exactly); default 1.5.
        [dimensionless]
    hematite : str, optional
        Hematite data: ``"querry-extraordinary"`` (default; E parallel to c,
        which reproduces the seed's table), ``"querry-ordinary"``,
        ``"querry-average"`` (eps = (2 eps_o + eps_e)/3), or the full
        catalogue name of one of them.
    rule : {"maxwell_garnett", "bruggeman"}, optional
        Mixing rule; default ``"maxwell_garnett"`` as in [1]_.

    Returns
    -------
    Mixture
        Valid over the hematite table's range (210-55555.6 nm for the
        extraordinary ray, 210-3876 nm for the ordinary ray and the average).

    Raises
    ------
    ValueError
        If ``hematite_fraction`` is outside [0, 1], ``host_index`` is not a
        valid index, or ``hematite`` or ``rule`` is unknown (the message lists
        the valid ones).
    TypeError
        If ``host_index`` is neither a number, a RefractiveIndex nor a str.

    Notes
    -----
    The seed thesis looked its hematite index up in the Amsterdam-Granada
    light-scattering database; the BRIEF (section 5) shows that Querry's
    extraordinary ray reproduces its published table to within its
    Monte-Carlo noise, hence the default.

    References
    ----------
    .. [1] K. Ehlers, R. Chakrabarty and H. Moosmüller, "Blue moons and
       Martian sunsets", Appl. Opt. 53, 1808-1819 (2014),
       doi:10.1364/AO.53.001808.
    .. [2] T. Meyran, "Physically Based Real-Time Rendering of the Martian
       Atmosphere", M.Sc. thesis, Hochschule Hannover (2022).

    Examples
    --------
    >>> mars_dust()(550.0)
    array(1.5336...+0.0071...j)
    """
    choices = (*MARS_DUST_HEMATITE, *MARS_DUST_HEMATITE.values())
    check_choice("hematite", hematite, choices)
    fraction = check_closed_interval("hematite_fraction", hematite_fraction, 0.0, 1.0)
    rule = check_choice("rule", rule, MIXING_RULES)
    host = _mars_dust_host(host_index)
    mineral = get_material(MARS_DUST_HEMATITE.get(hematite, hematite))
    name = f"mars-dust-ehlers2014({fraction:g} {mineral.name} in {host.name}, {rule})"
    citation = (
        f'{_EHLERS2014} (dust model); {_MEYRAN2022} ("Blue Moon\'s" model); '
        f"{_RULE_CITATIONS[rule]}; hematite: {mineral.citation}"
    )
    if not isinstance(host, ConstantIndex):  # a host with its own data names its source
        citation = f"{citation}; host: {host.citation}"
    return Mixture(
        host=host,
        inclusion=mineral,
        volume_fraction=fraction,
        rule=rule,
        name=name,
        citation=citation,
    )


def _mars_dust_host(host_index: Any) -> RefractiveIndex:
    """``host_index`` as a material; a string must be a catalogue name."""
    if isinstance(host_index, str) and host_index not in list_materials():
        raise ValueError(
            f"host_index must be a complex refractive index, a RefractiveIndex or a catalogue "
            f"name ({', '.join(list_materials())}); got {host_index!r}"
        )
    return as_refractive_index(host_index, name="host_index")
