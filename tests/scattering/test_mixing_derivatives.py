"""Derivatives of the mixing rules (Maxwell Garnett, Bruggeman) and of Mixture's
parameters, for compute_optics(derivatives=("hematite_fraction", ...)) (issue 30)."""

from __future__ import annotations

import numpy as np
import pytest

from dustoptics.particles.mixing import mars_dust

# ---------------------------------------------------------------- derivatives (issue 30)


@pytest.mark.parametrize("rule", ["maxwell_garnett", "bruggeman"])
@pytest.mark.parametrize(
    ("host", "inclusion", "v"),
    [
        (1.5 + 0.001j, 2.927 + 0.46j, 0.03),
        (1.33 + 0.01j, 3.0 + 1.0j, 0.4),
        (1.5 + 0.001j, 2.0, 0.0),
    ],
)
def test_rule_derivatives_against_central_differences(
    rule: str, host: complex, inclusion: complex, v: float
) -> None:
    """dm/dv and dm/dm_host (and i dm/dm_host along k_host) against central
    differences of the rule itself; step 1e-6, error O(1e-12) from the cubic term,
    round-off ~1e-16 / 1e-6 = 1e-10 (hosts absorb a little: k_host - h stays >= 0)."""
    from dustoptics.particles.mixing import (
        bruggeman,
        bruggeman_derivatives,
        maxwell_garnett,
        maxwell_garnett_derivatives,
    )

    f = {"maxwell_garnett": maxwell_garnett, "bruggeman": bruggeman}[rule]
    df = {"maxwell_garnett": maxwell_garnett_derivatives, "bruggeman": bruggeman_derivatives}[rule]
    d_v, d_h = df(host=host, inclusion=inclusion, volume_fraction=v)
    h = 1e-6
    lo, hi = (v, v + 2 * h) if v == 0.0 else (v - h, v + h)  # v >= 0: one-sided at 0 by 2h
    fd_v = (
        f(host=host, inclusion=inclusion, volume_fraction=hi)
        - f(host=host, inclusion=inclusion, volume_fraction=lo)
    ) / (hi - lo)
    tol_v = 1e-8 if v > 0.0 else 1e-5  # the one-sided difference errs by O(h)
    assert abs(complex(d_v) - complex(fd_v)) < tol_v * max(1.0, abs(complex(d_v)))
    for direction in (1.0, 1j):
        fd_h = (
            f(host=host + direction * h, inclusion=inclusion, volume_fraction=v)
            - f(host=host - direction * h, inclusion=inclusion, volume_fraction=v)
        ) / (2 * h)
        assert abs(direction * complex(d_h) - complex(fd_h)) < 1e-8 * max(1.0, abs(complex(d_h)))


def test_mixture_parameters_and_their_values() -> None:
    dust = mars_dust()
    assert dust.index_parameters == ("hematite_fraction", "volume_fraction", "host_n", "host_k")
    assert dust.parameter_value("hematite_fraction") == 0.03
    assert dust.parameter_value("host_n") == 1.5
    moved = dust.with_parameter("hematite_fraction", 0.05)
    assert moved.name == mars_dust(hematite_fraction=0.05).name
    np.testing.assert_array_equal(moved([550.0]), mars_dust(hematite_fraction=0.05)([550.0]))
    host = dust.with_parameter("host_k", 0.002)
    np.testing.assert_array_equal(host([550.0]), mars_dust(host_index=1.5 + 0.002j)([550.0]))
    with pytest.raises(ValueError, match="parameter"):
        dust.with_parameter("fraction", 0.1)
    wolff = mars_dust(host_index="marsdust-wolff2009")
    with pytest.raises(ValueError, match="constant host"):
        wolff.parameter_value("host_n")
