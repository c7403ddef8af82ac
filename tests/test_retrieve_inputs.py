"""dustoptics.retrieve's boundary: every input (observations, parameters, bounds,
priors, options) refused with a ValueError/TypeError naming it, its value and what is
allowed, before any table is computed; the fit's work estimated up front; a fit whose
data carry no information not called converged; the command line's own refusals
(``--model`` devices, ``--out`` over an input, declared sizes)."""

from __future__ import annotations

import json
import math
import os
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import dustoptics as do
import dustoptics.retrieve.fit as fit_module
from dustoptics._validation import BudgetError
from dustoptics.retrieve import retrieve

xr = pytest.importorskip("xarray")

WL = np.array([440.0, 550.0, 680.0])
MODEL = {
    "refractive_index": 1.5 + 0.01j,
    "distribution": do.ModifiedGamma(r_eff_um=0.5, v_eff=0.15),
}
BOUNDS = {"r_eff_um": (0.1, 3.0)}


class _Reached(Exception):
    """compute_optics was called: the inputs passed the boundary."""


@pytest.fixture
def no_tables(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any table computed raises _Reached: a refusal must come before it."""

    def refuse(*args: Any, **kwargs: Any) -> None:
        raise _Reached

    monkeypatch.setattr(fit_module, "compute_optics", refuse)


def _ssa(wavelength_nm: Any = WL, **attrs: Any) -> Any:
    values = np.full(np.shape(wavelength_nm), 0.93)
    attrs = {"uncertainty": 0.01, **attrs}
    return xr.Dataset(
        {"ssa": ("wavelength_nm", values, attrs)}, coords={"wavelength_nm": wavelength_nm}
    )


def _ratio(reference: Any) -> Any:
    attrs = {"uncertainty": 0.01, "reference_wavelength_nm": reference}
    return xr.Dataset(
        {"extinction_ratio": ("wavelength_nm", [1.1, 1.0, 0.9], attrs)},
        coords={"wavelength_nm": WL},
    )


def _phase(theta_deg: Any) -> Any:
    return xr.Dataset(
        {"phase": (("wavelength_nm", "theta_deg"), np.full((3, 3), 0.1), {"uncertainty": 0.01})},
        coords={"wavelength_nm": WL, "theta_deg": theta_deg},
    )


def _fit(observations: Any, **kwargs: Any) -> Any:
    arguments: dict[str, Any] = {"model": MODEL, "parameters": ["r_eff_um"], "bounds": BOUNDS}
    arguments.update(kwargs)
    return retrieve(observations, **arguments)


# ---------------------------------------------------------------- observations


@pytest.mark.parametrize(
    ("observations", "error", "match"),
    [
        (_phase([10.0, math.nan, 170.0]), ValueError, r"'phase' coordinate theta_deg .*\[nan\]"),
        (_phase([10.0, math.inf, 170.0]), ValueError, r"theta_deg must be finite .*\[inf\]"),
        (_phase([10.0, 90.0, 190.0]), ValueError, r"theta_deg .*within \[0, 180\]; got \[190"),
        (_ratio(math.nan), ValueError, r"reference_wavelength_nm must be one finite .*got nan"),
        (_ratio(0.0), ValueError, r"reference_wavelength_nm must be .*\(0, 1e\+07\] nm; got 0"),
        (_ratio(math.inf), ValueError, r"reference_wavelength_nm .*got inf"),
        (_ratio("550"), ValueError, r"reference_wavelength_nm .*got '550'"),
        (_ssa([0.0, 550.0, 680.0]), ValueError, r"'ssa' coordinate wavelength_nm .*got \[0\.0\]"),
        (_ssa([-5.0, 550.0, 680.0]), ValueError, r"wavelength_nm .*\(0, 1e\+07\]; got \[-5\.0\]"),
        (_ssa([math.nan, 550.0, 680.0]), ValueError, r"wavelength_nm must be finite.*\[nan\]"),
        (_ssa(["a", "b", "c"]), TypeError, r"'ssa' coordinate wavelength_nm must be real numbers"),
        (_ssa(uncertainty="x"), TypeError, r"'ssa' attribute uncertainty must be real numbers"),
        (_ssa(uncertainty=[0.1, 0.2]), ValueError, r"uncertainty must be one number; got \[0\.1"),
        (_ssa(uncertainty=0.0), ValueError, r"'ssa' uncertainties must be finite and > 0; got \[0"),
        (_ssa(uncertainty=math.inf), ValueError, r"uncertainties must be finite .*got \[inf"),
        (
            xr.Dataset({"ssa": ("wavelength_nm", ["a", "b", "c"], {"uncertainty": 0.01})}),
            TypeError,
            r"'ssa' values must be real numbers; got dtype <U1",
        ),
        (
            xr.Dataset({"ssa": ("wavelength_nm", [0.9, 0.9], {"uncertainty": 0.01})}),
            ValueError,
            r"'ssa' needs the coordinate 'wavelength_nm'",
        ),
        ({"ssa": [0.9]}, TypeError, r"observations must be an xarray Dataset .*got dict"),
    ],
)
def test_observations_are_refused_naming_the_variable_and_value(
    no_tables: None, observations: Any, error: type[Exception], match: str
) -> None:
    with pytest.raises(error, match=match):
        _fit(observations)


def test_units_of_the_coordinates_are_checked(no_tables: None) -> None:
    in_um = _ssa().assign_coords(wavelength_nm=("wavelength_nm", WL / 1e3, {"units": "um"}))
    with pytest.raises(ValueError, match=r"wavelength_nm must be in nm; got units='um'"):
        _fit(in_um)
    in_nm = _ssa().assign_coords(wavelength_nm=("wavelength_nm", WL, {"units": "nm"}))
    with pytest.raises(_Reached):
        _fit(in_nm)


def test_an_uncertainty_variable_of_another_shape_is_refused(no_tables: None) -> None:
    obs = _ssa()
    obs["ssa_uncertainty"] = ("other", [0.01, 0.02])
    with pytest.raises(ValueError, match=r"'ssa_uncertainty' must have dimensions among"):
        _fit(obs.drop_vars("other", errors="ignore"))


@given(
    st.lists(
        st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10, 10**6)),
        min_size=1,
        max_size=4,
    )
)
def test_any_wavelength_grid_is_a_named_refusal_or_reaches_the_table(
    wavelength_nm: list[float],
) -> None:
    """Whatever numbers the coordinate holds: a ValueError naming wavelength_nm, or a
    valid grid that reaches the first table (BudgetError counts: it is an estimate)."""
    obs = _ssa(np.array(wavelength_nm, dtype=np.float64))
    original = fit_module.compute_optics

    def refuse(*args: Any, **kwargs: Any) -> None:
        raise _Reached

    fit_module.compute_optics = refuse  # type: ignore[assignment]
    try:
        _fit(obs, max_iterations=1)
    except _Reached:
        assert all(0 < w <= 1e7 for w in wavelength_nm)
    except BudgetError as exc:
        assert "would need" in str(exc) or "memory" in str(exc)
    except ValueError as exc:
        assert "wavelength_nm" in str(exc) or "index" in str(exc), exc
    finally:
        fit_module.compute_optics = original  # type: ignore[assignment]


# ---------------------------------------------------------------- bounds, priors, options


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"bounds": {"r_eff_um": (0.1,)}}, ValueError, r"bounds\['r_eff_um'\] .*got \(0\.1,\)"),
        ({"bounds": {"r_eff_um": (0.1, 1, 2)}}, ValueError, r"of two numbers; got \(0\.1, 1, 2\)"),
        ({"bounds": {"r_eff_um": "0.1:3"}}, TypeError, r"bounds\['r_eff_um'\] .*got '0\.1:3'"),
        ({"bounds": {"r_eff_um": None}}, TypeError, r"bounds\['r_eff_um'\] must be a pair"),
        ({"bounds": {"r_eff_um": ("0.1", 3)}}, TypeError, r"two real numbers .*\('0\.1', 3\)"),
        ({"bounds": [(0.1, 3.0)]}, TypeError, r"bounds must be a mapping .*got list"),
        ({"priors": {"r_eff_um": (0.5,)}}, ValueError, r"priors\['r_eff_um'\] .*got \(0\.5,\)"),
        ({"priors": {"r_eff_um": ("a", 1)}}, TypeError, r"priors\['r_eff_um'\] must hold two"),
        (
            {"priors": {"r_eff_um": (0.5, -1.0)}},
            ValueError,
            r"deviation > 0; got mean=0\.5, sd=-1\.0",
        ),
        ({"priors": [1, 2]}, TypeError, r"priors must be a mapping .*got list"),
        ({"parameters": "r_eff_um"}, TypeError, r"parameters must be a sequence .*'r_eff_um'"),
        ({"parameters": 3}, TypeError, r"parameters must be a sequence .*got 3"),
        ({"parameters": ["bogus"]}, ValueError, r"parameters: unknown parameter 'bogus'"),
        ({"max_iterations": True}, ValueError, r"max_iterations .*\[1, 100000\]; got True"),
        ({"max_iterations": 3.0}, ValueError, r"max_iterations must be an integer.*got 3\.0"),
        ({"max_iterations": 10**20}, ValueError, r"max_iterations .*got 100000000000000000000"),
        ({"tolerance": "1e-6"}, ValueError, r"tolerance must be .*\[1e-15, 1\); got '1e-6'"),
        ({"tolerance": 0.0}, ValueError, r"tolerance must be a number .*got 0\.0"),
        ({"tolerance": math.nan}, ValueError, r"tolerance must be a number .*got nan"),
        ({"allow_large": "yes"}, TypeError, r"allow_large must be True or False; got 'yes'"),
    ],
)
def test_arguments_are_refused_naming_the_parameter_and_value(
    no_tables: None, kwargs: dict[str, Any], error: type[Exception], match: str
) -> None:
    with pytest.raises(error, match=match):
        _fit(_ssa(), **kwargs)


@given(
    st.one_of(
        st.none(),
        st.text(max_size=4),
        st.lists(
            st.one_of(st.floats(), st.text(max_size=2), st.none(), st.booleans()), max_size=3
        ).map(tuple),
    )
)
def test_any_bound_is_a_named_refusal_or_a_valid_pair(bound: Any) -> None:
    """A bound of any shape: ValueError/TypeError naming bounds, never an internal error."""
    original = fit_module.compute_optics

    def refuse(*args: Any, **kwargs: Any) -> None:
        raise _Reached

    fit_module.compute_optics = refuse  # type: ignore[assignment]
    try:
        _fit(_ssa(), bounds={"r_eff_um": bound}, max_iterations=1)
    except _Reached:
        assert len(bound) == 2 and bound[0] <= 0.5 <= bound[1]
    except (ValueError, TypeError) as exc:
        assert str(exc).startswith("bounds"), exc
    finally:
        fit_module.compute_optics = original  # type: ignore[assignment]


def test_the_fit_s_work_is_estimated_before_any_table(no_tables: None) -> None:
    """100,000 wavelengths: refused at once with the estimate; fewer evaluations or
    allow_large go ahead (to the first table)."""
    wavelength_nm = np.linspace(400.0, 900.0, 100_000)
    with pytest.raises(BudgetError, match=r"about [0-9.e+]+ sphere-order-angle terms .*100000 wa"):
        _fit(_ssa(wavelength_nm))
    with pytest.raises(_Reached):
        _fit(_ssa(wavelength_nm), max_iterations=5)
    with pytest.raises(_Reached):
        _fit(_ssa(wavelength_nm), allow_large=True)


# ---------------------------------------------------------------- no information


def test_a_fit_whose_data_carry_no_information_is_not_converged() -> None:
    """An uncertainty of 1e308: not converged, the message says why, the standard error
    is infinite (not 0); a prior on a second parameter still informs it."""
    flat = _fit(_ssa(uncertainty=1e308), max_iterations=5)
    assert not flat.converged
    assert "no information on r_eff_um" in flat.message
    assert flat.standard_errors.tolist() == [math.inf]
    both = _fit(
        _ssa(uncertainty=1e308),
        parameters=["r_eff_um", "k"],
        bounds={**BOUNDS, "k": (0.0, 0.05)},
        priors={"k": (0.01, 0.001)},
        max_iterations=5,
    )
    assert not both.converged and "no information on r_eff_um:" in both.message
    assert both.standard_error("r_eff_um") == math.inf
    assert both.standard_error("k") == pytest.approx(0.001, rel=1e-6)


def test_uninformed_columns() -> None:
    """The test behind it: zero, underflowing and degenerate columns, not good ones."""
    good = np.array([[1.0, 0.0], [0.0, 2.0], [1.0, 1.0]])
    width = np.array([1.0, 1.0])
    assert fit_module._uninformed(good, width).tolist() == [False, False]
    assert fit_module._uninformed(good * 1e-300, width).tolist() == [True, True]
    tiny = good.copy()
    tiny[:, 1] *= 1e-320  # subnormal: its square underflows to 0
    assert fit_module._uninformed(tiny, width).tolist() == [False, True]
    same = np.array([[1.0, 1.0], [2.0, 2.0]])
    assert fit_module._uninformed(same, width).tolist() == [True, True]
    assert fit_module._uninformed(np.zeros((3, 1)), width[:1]).tolist() == [True]


# ---------------------------------------------------------------- the command line


def _files(tmp_path: Any) -> tuple[Any, Any]:
    obs = tmp_path / "obs.nc"
    _ssa().to_netcdf(obs)
    config = tmp_path / "dust.toml"
    config.write_text(
        'name = "start"\ndescription = "a start for the fit"\n'
        '[material]\nmodel = "constant"\nn = 1.5\nk = 0.01\n'
        '[size_distribution]\nmodel = "modified_gamma"\nr_eff_um = 0.5\nv_eff = 0.15\n',
        encoding="utf-8",
    )
    return obs, config


def test_command_line_never_writes_over_its_inputs(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    from dustoptics.cli import main

    obs, config = _files(tmp_path)
    before = obs.read_bytes(), config.read_bytes()
    fit = ["--fit", "r_eff_um=0.1:3", "--force"]
    for out, what in ((obs, "observations file"), (config, "--model file")):
        assert main(["retrieve", str(obs), "--model", str(config), *fit, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert f"--out {out} is the {what} {out}" in err and "never writes over" in err
    link = tmp_path / "link.nc"
    link.symlink_to(obs)
    assert main(["retrieve", str(obs), "--model", str(config), *fit, "--out", str(link)]) == 2
    assert "is the observations file" in capsys.readouterr().err
    assert (obs.read_bytes(), config.read_bytes()) == before


def test_command_line_refuses_a_model_that_is_not_a_regular_file(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    from dustoptics.cli import main

    obs, _ = _files(tmp_path)
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)
    for model in ("/dev/zero", str(fifo)):
        assert main(["retrieve", str(obs), "--model", model, "--fit", "r_eff_um=0.1:3"]) == 1
        err = capsys.readouterr().err
        assert f"--model {model}: not a regular file" in err, err
        assert len(err.strip().splitlines()) == 1


def test_command_line_bounds_the_declared_size_before_reading(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 4e8-value ssa in a file of a few KiB: refused from its declared size; the limit
    is an option."""
    h5netcdf = pytest.importorskip("h5netcdf")
    from dustoptics.cli import main

    _, config = _files(tmp_path)
    bomb = tmp_path / "bomb.nc"
    with h5netcdf.File(bomb, "w") as f:
        f.dimensions = {"wavelength_nm": 400_000_000}
        var = f.create_variable("ssa", ("wavelength_nm",), "f8", chunks=(1_000_000,))
        var.attrs["uncertainty"] = 0.01
    assert bomb.stat().st_size < 100_000
    argv = ["retrieve", str(bomb), "--model", str(config), "--fit", "r_eff_um=0.1:3"]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "declare 3200000000 bytes in memory ('ssa': 3200000000 bytes" in err, err
    assert "--max-observation-bytes" in err
    obs, _ = _files(tmp_path)
    assert main([*argv[:1], str(obs), *argv[2:], "--max-observation-bytes", "100"]) == 1
    assert "larger than the 100-byte limit" in capsys.readouterr().err
    assert main([*argv[:1], str(obs), *argv[2:], "--max-observation-bytes", "0"]) == 2
    assert "--max-observation-bytes must be >= 1; got 0" in capsys.readouterr().err


def test_command_line_reports_an_uninformative_fit(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    from dustoptics.cli import main

    obs, config = _files(tmp_path)
    _ssa(uncertainty=1e308).to_netcdf(obs)
    out = tmp_path / "fit.json"
    argv = ["retrieve", str(obs), "--model", str(config), "--fit", "r_eff_um=0.1:3"]
    assert main([*argv, "--max-iterations", "5", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "NOT converged" in printed and "no information on r_eff_um" in printed
    record = json.loads(out.read_text(encoding="utf-8"))
    assert record["converged"] is False and record["standard_errors"] == [None]


def test_command_line_bounds_the_iterations(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    from dustoptics.cli import main

    obs, config = _files(tmp_path)
    argv = ["retrieve", str(obs), "--model", str(config), "--fit", "r_eff_um=0.1:3"]
    for n in ("0", "99999999999999999999"):
        assert main([*argv, "--max-iterations", n]) == 2
        assert f"--max-iterations must be within [1, 100000]; got {n}" in capsys.readouterr().err
