"""The ``disort`` file, read back by an independent reader (numpy.loadtxt for the rows,
DISORT's moment definition for the values) and by CDISORT itself, and compared with the
Table."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _rt_table import rt_table

import dustoptics as do
from dustoptics.cli import main
from dustoptics.io import FORMATS, write


@pytest.fixture(scope="module")
def table() -> do.Table:
    return rt_table()


def _header(path: Path) -> list[str]:
    return [ln for ln in path.read_text().splitlines() if ln.startswith("#")]


def test_registered() -> None:
    assert "disort" in FORMATS


def test_disort_file(table: do.Table, tmp_path: Path) -> None:
    (path,) = write(table, tmp_path, format="disort")
    assert path.name == "mars_rt_disort.txt"
    rows = np.loadtxt(path, ndmin=2)
    np.testing.assert_array_equal(rows[:, 0], table.wavelength_nm)
    np.testing.assert_array_equal(rows[:, 1], table.cross_sections.cext_um2)
    np.testing.assert_array_equal(
        rows[:, 2], table.cross_sections.csca_um2 / table.cross_sections.cext_um2
    )
    np.testing.assert_array_equal(rows[:, 3], table.expansion.expansion_error_estimate)
    n_mom = table.expansion.alpha1.shape[1]
    pmom = rows[:, 4 : 4 + n_mom]
    # The phase block: 4 pi F11 at the cosines of the table's angles, 180 deg first.
    phase = rows[:, 4 + n_mom :]
    np.testing.assert_allclose(phase, 4 * np.pi * table.phase[:, ::-1], rtol=1e-15, atol=0)
    (mu_line,) = [h for h in _header(path) if h.startswith("# mu_phase: ")]
    mu = np.array(mu_line.split()[2:], dtype=float)
    np.testing.assert_allclose(mu, np.cos(np.radians(table.theta_deg[::-1])), atol=1e-15)
    assert mu[0] == -1.0 and mu[-1] == 1.0 and np.all(np.diff(mu) > 0)
    # Normalized like the moments: the Legendre series sum_l (2l+1) pmom_l P_l(mu) is it.
    l_ = np.arange(n_mom)
    series = np.polynomial.legendre.legval(mu, ((2 * l_ + 1) * pmom).T)
    np.testing.assert_allclose(phase, series, rtol=1e-3)
    # DISORT's moments: chi_l = alpha1_l / (2 l + 1), computed here independently.
    l_ = np.arange(table.expansion.alpha1.shape[1])
    np.testing.assert_allclose(pmom, table.expansion.alpha1 / (2 * l_ + 1), rtol=1e-15, atol=0)
    # Identities: chi_0 = 1 (normalization), chi_1 = g (asymmetry parameter).
    np.testing.assert_array_equal(pmom[:, 0], 1.0)
    np.testing.assert_allclose(pmom[:, 1], table.g, atol=1e-6)
    head = "\n".join(_header(path))
    assert table.provenance.input_hash in head
    assert "[um2]" in head and "[nm]" in head and "pmom_l = alpha1_l / (2 l + 1)" in head
    # Deterministic: the same table gives the same bytes.
    (again,) = write(table, tmp_path / "again", format="disort")
    assert again.read_bytes() == path.read_bytes()


def test_refusals(table: do.Table, tmp_path: Path) -> None:
    plain = table.replace(
        expansion=None,
    )
    with pytest.raises(ValueError, match=r"expansion=True"):
        write(plain, tmp_path, format="disort")
    with pytest.raises(ValueError, match="cross-sections"):
        write(table.replace(cross_sections=None), tmp_path, format="disort")
    assert list(tmp_path.iterdir()) == []


def test_cli_export(table: do.Table, tmp_path: Path) -> None:
    src = tmp_path / "t.nc"
    table.save(src)
    out = tmp_path / "out"
    assert main(["export", str(src), "--out", str(out), "--format", "disort,libradtran"]) == 0
    files = sorted(p.name for p in out.rglob("*") if p.is_file())
    assert files == [
        "mars_rt_aerosol_explicit.dat",
        "mars_rt_aerosol_layer.dat",
        "mars_rt_disort.txt",
    ]
    (disort,) = out.rglob("mars_rt_disort.txt")
    np.testing.assert_array_equal(np.loadtxt(disort, ndmin=2)[:, 1], table.cross_sections.cext_um2)
    # The table has a number density: its default profile, one uniform layer 0-1 km.
    layers = [h for h in _header(disort) if h.startswith("# layer: ") and "bottom" not in h]
    assert layers == [f"# layer: 0.0 1.0 {2.0e6 * 1e3 * 1e-12!r}"]


def test_cli_refuses_without_expansion(
    table: do.Table, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = tmp_path / "plain.nc"
    table.replace(
        expansion=None,
    ).save(src)
    code = main(["export", str(src), "--out", str(tmp_path / "out"), "--format", "disort"])
    assert code != 0
    assert "expansion=True" in capsys.readouterr().err
    assert not list((tmp_path / "out").rglob("*.txt"))


def test_cli_build_refuses_what_it_cannot_compute_before_computing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A Mie model's expansion is computed when asked for (tests/cli/test_cli_build.py); an
    # analytic phase function has neither the expansion nor cross-sections.
    code = main(["build", "costa", "--out", str(tmp_path), "--format", "disort", "--quiet"])
    assert code == 2
    err = capsys.readouterr().err
    assert "--format disort needs cross-sections, which 'costa' does not have" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("sza_deg", [60.0, 30.0])
def test_cdisort_reads_the_moments(table: do.Table, tmp_path: Path, sza_deg: float) -> None:
    """CDISORT (nanodisort) given the file's ssa and moments: the nadir radiance
    leaving an optically thin layer is single scattering (Chandrasekhar 1950;
    Thomas & Stamnes 1999, eq. 7.12),
    I = F0 ssa F11(Theta) mu0 / (mu0 + mu) (1 - exp(-tau (1/mu0 + 1/mu))),
    with F11 from the table's tabulated phase function at Theta = 180 - sza
    (per sr, so F0/(4 pi) P = F0 F11); multiple scattering adds O(tau)."""
    nanodisort = pytest.importorskip("nanodisort")
    (path,) = write(table, tmp_path, format="disort")
    row = np.loadtxt(path, ndmin=2)[0]
    ssa, pmom = row[2], row[4 : 4 + table.expansion.alpha1.shape[1]]
    tau, mu0, mu = 1e-3, np.cos(np.radians(sza_deg)), 1.0
    s = nanodisort.DisortState()
    s.nstr, s.nlyr, s.nmom, s.ntau, s.numu, s.nphi = 16, 1, pmom.size - 1, 1, 1, 1
    s.usrtau = s.usrang = s.lamber = s.quiet = True
    s.onlyfl = False
    s.intensity_correction = s.old_intensity_correction = True
    s.allocate()
    s.dtauc, s.ssalb, s.pmom = np.array([tau]), np.array([ssa]), pmom.reshape(-1, 1)
    s.utau, s.umu, s.phi = np.array([0.0]), np.array([mu]), np.array([0.0])
    s.fbeam, s.umu0, s.phi0, s.albedo = 1.0, mu0, 0.0, 0.0
    s.solve()
    (k,) = np.flatnonzero(table.theta_deg == 180.0 - sza_deg)
    single = ssa * table.phase[0, k] * mu0 / (mu0 + mu) * (1 - np.exp(-tau * (1 / mu0 + 1 / mu)))
    np.testing.assert_allclose(np.asarray(s.uu).ravel()[0], single, rtol=1e-2)


@pytest.mark.parametrize("view_zenith_deg", [50.0, 40.0])
def test_cdisort_reads_the_phase_block(
    table: do.Table, tmp_path: Path, view_zenith_deg: float
) -> None:
    """CDISORT's intensity correction of Buras, Dowling and Emde (2011) given the file's
    phase block: the sky radiance near the Sun under an optically thin layer is single
    scattering (Thomas & Stamnes 1999, eq. 7.13 for the transmitted beam),
    I = F0 ssa F11(Theta) mu0 / (mu0 - mu) (exp(-tau/mu0) - exp(-tau/mu)),
    with F11 the table's at Theta = view zenith - Sun zenith (10 and 20 deg), whatever
    the moments: given 24 moments only, it holds with the block, and the moments alone
    (the older correction of Nakajima and Tanaka) miss the forward peak."""
    nanodisort = pytest.importorskip("nanodisort")
    (path,) = write(table, tmp_path, format="disort")
    from dustoptics.io.rt.disort import read_disort

    f = read_disort(path)
    ssa, pmom = f.ssa[0], f.pmom[0, :25]
    tau, sza = 1e-3, 30.0
    mu0, mu = np.cos(np.radians(sza)), np.cos(np.radians(view_zenith_deg))

    def radiance(with_phase: bool) -> float:
        s = nanodisort.DisortState()
        s.nstr, s.nlyr, s.nmom, s.ntau, s.numu, s.nphi = 16, 1, pmom.size - 1, 1, 1, 1
        s.nphase = f.mu_phase.size if with_phase else 0
        s.usrtau = s.usrang = s.lamber = s.quiet = True
        s.onlyfl = False
        s.intensity_correction = True
        s.old_intensity_correction = not with_phase
        s.allocate()
        s.dtauc, s.ssalb, s.pmom = np.array([tau]), np.array([ssa]), pmom.reshape(-1, 1)
        if with_phase:
            s.mu_phase = f.mu_phase
            s.phase = f.phase[:1].copy()
        s.utau, s.umu, s.phi = np.array([tau]), np.array([-mu]), np.array([0.0])
        s.fbeam, s.umu0, s.phi0, s.albedo = 1.0, mu0, 0.0, 0.0
        s.solve()
        return float(np.asarray(s.uu).ravel()[0])

    (k,) = np.flatnonzero(table.theta_deg == view_zenith_deg - sza)
    single = ssa * table.phase[0, k] * mu0 / (mu0 - mu) * (np.exp(-tau / mu0) - np.exp(-tau / mu))
    np.testing.assert_allclose(radiance(True), single, rtol=1e-2)
    assert abs(radiance(False) / single - 1.0) > 0.05
