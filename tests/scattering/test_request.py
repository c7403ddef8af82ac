"""compute_optics as request -> solve -> assemble: the request is validated once and recorded."""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest

import dustoptics as do
from dustoptics._validation import BudgetError
from dustoptics.models.compute import build_table, mie_request
from dustoptics.models.presets import load_preset
from dustoptics.scattering.optics import (
    ConvergenceWarning,
    OpticsRequest,
    check_cost,
    compute_request,
    optics_request,
    recompute,
)
from dustoptics.scattering.quadrature import QuadratureSettings
from dustoptics.table import canonical_json, plain

DIST = do.ModifiedGamma(r_eff_um=0.5, v_eff=0.1)
WL = [450.0, 650.0]
THETA = np.linspace(0.0, 180.0, 37)


def test_the_request_is_frozen_and_holds_the_defaults_filled_in() -> None:
    request = optics_request(1.5 + 0.01j, DIST, WL, THETA, rtol=1e-3)
    assert isinstance(request, OpticsRequest)
    assert request.cross_section_rtol == pytest.approx(1e-5)
    assert request.weighting == "scattering" and request.quadrature == QuadratureSettings()
    assert request.expansion_order is None and request.derivatives == ()
    np.testing.assert_array_equal(request.m, np.full(2, 1.5 + 0.01j))
    with pytest.raises(dataclasses.FrozenInstanceError):
        request.rtol = 1e-2  # type: ignore[misc]
    with pytest.raises(ValueError, match="read-only"):
        request.m[0] = 2.0


def test_compute_optics_is_its_request_computed() -> None:
    """The front door and the request's steps give the same table to the bit."""
    kwargs = {"rtol": 1e-3, "weighting": "number", "polarization": True, "expansion": 8}
    table = do.compute_optics(1.5 + 0.01j, DIST, WL, THETA, workers=1, **kwargs)
    again = compute_request(optics_request(1.5 + 0.01j, DIST, WL, THETA, **kwargs), workers=2)
    assert again.equals(table)
    assert canonical_json(plain(again.provenance.inputs)) == canonical_json(
        plain(table.provenance.inputs)
    )


def test_the_provenance_records_the_request() -> None:
    request = optics_request(do.mars_dust(), DIST, WL, THETA, rtol=1e-3, expansion=True)
    table = compute_request(request, workers=1)
    assert canonical_json(plain(table.provenance.inputs)) == canonical_json(plain(request.inputs()))
    assert table.provenance.inputs["expansion"] is True
    assert "polarization" not in table.provenance.inputs  # recorded only when used
    assert recompute(table.provenance, workers=1).equals(table)


@pytest.mark.parametrize("argument", ["rtol", "weighting"])
def test_tolerance_and_weighting_are_keyword_only(argument: str) -> None:
    value = {"rtol": 1e-3, "weighting": "number"}[argument]
    position = [THETA, 1e-3] if argument == "rtol" else [THETA, 1e-3, "number"]
    with pytest.raises(TypeError, match="positional"):
        do.compute_optics(1.5, DIST, WL, *position)
    with pytest.raises(TypeError, match="positional"):
        optics_request(1.5, DIST, WL, *position)
    assert optics_request(1.5, DIST, WL, THETA, **{argument: value}) is not None


def test_the_old_spelling_of_the_wavelengths_is_gone() -> None:
    with pytest.raises(TypeError, match="wavelengths_nm"):
        do.compute_optics(1.5, DIST, wavelengths_nm=WL)  # type: ignore[call-arg]


def test_bad_input_is_refused_by_the_request_before_any_work() -> None:
    with pytest.raises(ValueError, match="weighting"):
        optics_request(1.5, DIST, WL, weighting="area")
    with pytest.raises(ValueError, match="expansion"):
        optics_request(1.5, DIST, WL, expansion=-1)
    with pytest.raises(ValueError, match="k >= 0"):
        optics_request(1.5 - 0.1j, DIST, WL)
    with pytest.raises(TypeError, match="OpticsRequest"):
        compute_request({"rtol": 1e-3})  # type: ignore[arg-type]


def test_the_cost_check_takes_the_request() -> None:
    big = optics_request(1.5, do.Monodisperse(radius_um=1e4), [360.0, 830.0])
    with pytest.raises(BudgetError, match="compute_optics would need"):
        check_cost(big, workers=2, allow_large=False)
    assert check_cost(big, workers=2, allow_large=True).memory_bytes > 5e9
    with pytest.raises(BudgetError):
        compute_request(big, workers=2)


def test_a_configuration_is_built_from_its_request() -> None:
    config = load_preset("blue-moons")
    optics = dataclasses.replace(config.optics, wavelengths_nm=(450.0, 650.0), n_theta=19)
    config = dataclasses.replace(config, optics=optics)
    request = mie_request(config)
    assert request.rtol == config.optics.rtol and request.weighting == config.optics.weighting
    table = build_table(config, workers=1)
    direct = compute_request(request, workers=1, name=config.name)
    np.testing.assert_array_equal(table.phase, direct.phase)
    np.testing.assert_array_equal(table.cross_sections.cext_um2, direct.cross_sections.cext_um2)
    part = mie_request(config, wavelength_nm=np.array([650.0]))
    np.testing.assert_array_equal(part.m, request.m[1:])


@pytest.mark.parametrize("entry", ["compute_optics", "compute_request"])
def test_the_convergence_warning_points_at_the_caller(entry: str) -> None:
    kwargs = {"rtol": 1e-3, "quadrature": QuadratureSettings(max_level=0)}
    dist = do.ModifiedGamma(r_eff_um=3.0, v_eff=0.2)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if entry == "compute_optics":
            do.compute_optics(1.5 + 0.01j, dist, [550.0], THETA, workers=1, **kwargs)
        else:
            compute_request(optics_request(1.5 + 0.01j, dist, [550.0], THETA, **kwargs))
    found = [w for w in caught if issubclass(w.category, ConvergenceWarning)]
    assert found and Path(found[0].filename) == Path(__file__)


def test_no_public_function_of_the_computation_is_too_complex() -> None:
    """Cyclomatic complexity (radon) at most 20 for the public functions of the
    request, solve, assemble and sweep modules (issue 37)."""
    radon = pytest.importorskip("radon.complexity")
    root = Path(do.__file__).parent
    files = [
        root / "scattering" / name
        for name in ("optics.py", "solve.py", "table_derivatives.py", "refinement.py")
    ] + [root / "models" / "compute.py", *sorted((root / "sweep").glob("*.py"))]
    too_complex = []
    for path in files:
        for block in radon.cc_visit(path.read_text(encoding="utf-8")):
            public = not block.name.startswith("_")
            if public and block.complexity > 20:
                too_complex.append(f"{path.name}:{block.name} ({block.complexity})")
    assert not too_complex
