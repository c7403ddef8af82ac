"""Tests of dustoptics.plot: figures hold the table's own numbers; saving is atomic and reproducible.

The table is built by hand from Henyey-Greenstein phase functions, so every
value a figure should show is known independently of the plotting code.
Tests that draw need matplotlib (``pytest.importorskip``); the tests of the
behaviour without matplotlib run everywhere.
"""

from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from dustoptics import plot
from dustoptics.scattering.phase import henyey_greenstein
from dustoptics.table import CrossSections, Table

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"

WAVELENGTH_NM = np.array([450.0, 550.0, 650.0])
G = np.array([0.8, 0.7, 0.6])
CEXT_UM2 = np.array([3.0, 2.8, 2.6])
CSCA_UM2 = np.array([2.5, 2.5, 2.4])


@pytest.fixture
def mpl():
    return pytest.importorskip("matplotlib")


@pytest.fixture
def table() -> Table:
    theta = np.linspace(0.0, 180.0, 181)
    mu = np.cos(np.deg2rad(theta))
    phase = np.array([henyey_greenstein(mu, g=g) for g in G])
    return Table(
        name="hg-test",
        wavelength_nm=WAVELENGTH_NM,
        theta_deg=theta,
        phase=phase,
        g=G,
        cross_sections=CrossSections(cext_um2=CEXT_UM2, csca_um2=CSCA_UM2),
    )


@pytest.fixture
def phase_only(table: Table) -> Table:
    return table.replace(name="hg-phase-only", cross_sections=None)


# ---------------------------------------------------------------- phase_function


def test_phase_function_lines_are_the_tables_data(mpl, table):
    fig = plot.phase_function(table)
    assert isinstance(fig, mpl.figure.Figure)
    (ax,) = fig.axes
    assert ax.get_yscale() == "log"
    assert "[deg]" in ax.get_xlabel()
    assert "[sr" in ax.get_ylabel()
    assert "hg-test" in ax.get_title()
    lines = ax.get_lines()
    assert [line.get_label() for line in lines] == ["450 nm", "550 nm", "650 nm"]
    theta = np.linspace(0.0, 180.0, 181)
    mu = np.cos(np.deg2rad(theta))
    for line, g in zip(lines, G):
        np.testing.assert_array_equal(line.get_xdata(), theta)
        # Independent of the table object: the analytic function it was built from.
        np.testing.assert_allclose(line.get_ydata(), henyey_greenstein(mu, g=g), rtol=1e-15)


def test_phase_function_chosen_wavelengths_in_given_order(mpl, table):
    fig = plot.phase_function(table, wavelengths_nm=[650, 450.0, 650.0])
    lines = fig.axes[0].get_lines()
    assert [line.get_label() for line in lines] == ["650 nm", "450 nm"]
    np.testing.assert_array_equal(lines[0].get_ydata(), table.phase[2])
    np.testing.assert_array_equal(lines[1].get_ydata(), table.phase[0])
    single = plot.phase_function(table, wavelengths_nm=550.0)
    (line,) = single.axes[0].get_lines()
    np.testing.assert_array_equal(line.get_ydata(), table.phase[1])


def test_phase_function_accepts_text_round_off_of_a_grid_wavelength(mpl, table):
    fig = plot.phase_function(table, wavelengths_nm=[550.0 * (1 + 1e-12)])
    np.testing.assert_array_equal(fig.axes[0].get_lines()[0].get_ydata(), table.phase[1])


def test_phase_function_default_selects_at_most_seven_including_ends(mpl):
    wl = np.linspace(400.0, 700.0, 20)
    theta = np.linspace(0.0, 180.0, 19)
    g = np.linspace(0.5, 0.8, 20)
    phase = henyey_greenstein(np.cos(np.deg2rad(theta))[None, :], g=g[:, None])
    t = Table(name="many", wavelength_nm=wl, theta_deg=theta, phase=phase, g=g)
    lines = plot.phase_function(t).axes[0].get_lines()
    assert len(lines) == plot.MAX_DEFAULT_WAVELENGTHS
    assert lines[0].get_label() == "400 nm"
    assert lines[-1].get_label() == "700 nm"


def test_phase_function_polar(mpl, table):
    fig = plot.phase_function(table, wavelengths_nm=[550], polar=True)
    (ax,) = fig.axes
    assert ax.name == "polar"
    assert ax.get_yscale() == "log"  # the radial axis
    assert "[deg]" in ax.get_xlabel()
    assert "[sr" in ax.get_ylabel()
    assert "hg-test" in ax.get_title()
    (line,) = ax.get_lines()
    np.testing.assert_array_equal(line.get_xdata(), np.deg2rad(table.theta_deg))
    np.testing.assert_array_equal(line.get_ydata(), table.phase[1])
    # A half disc: forward scattering at 0, backward at pi.
    assert np.rad2deg(ax.get_xlim()[0]) == pytest.approx(0.0)
    assert np.rad2deg(ax.get_xlim()[1]) == pytest.approx(180.0)


def test_polar_half_disc_fills_the_figure_and_its_labels_do_not_overlap(mpl, table):
    """The half disc spans most of the figure's width, inside the figure; the radial tick
    labels (one per decade) and the axis labels are inside the figure and apart."""
    fig = plot.phase_function(table, polar=True)
    (ax,) = fig.axes
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    figure_box = fig.bbox
    wedge = ax.patch.get_window_extent(renderer)
    assert wedge.width >= 0.6 * figure_box.width
    assert wedge.height >= 0.5 * figure_box.height
    assert figure_box.x0 <= wedge.x0 and wedge.x1 <= figure_box.x1
    assert figure_box.y0 <= wedge.y0 and wedge.y1 <= figure_box.y1
    labels = [t for t in ax.get_yticklabels() if t.get_visible() and t.get_text()]
    labels += [ax.xaxis.label, ax.yaxis.label, ax.title]
    boxes = [t.get_window_extent(renderer) for t in labels]
    assert len(boxes) >= 5
    for i, a in enumerate(boxes):
        assert figure_box.x0 <= a.x0 and a.x1 <= figure_box.x1, labels[i].get_text()
        assert figure_box.y0 <= a.y0 and a.y1 <= figure_box.y1, labels[i].get_text()
        for b in boxes[i + 1 :]:
            assert not a.overlaps(b), (labels[i].get_text(), a, b)


def test_phase_function_wavelength_not_in_grid_lists_the_nearest(table):
    # Checked before matplotlib is needed: runs without it too.
    with pytest.raises(
        ValueError, match=r"wavelengths_nm: 551 nm is not in .* nearest in the grid: 550, 650 nm"
    ):
        plot.phase_function(table, wavelengths_nm=[550, 551])
    with pytest.raises(ValueError, match=r"1000 nm is not in .* nearest in the grid: 650 nm"):
        plot.phase_function(table, wavelengths_nm=1000)
    with pytest.raises(ValueError, match=r"300 nm is not in .* nearest in the grid: 450 nm"):
        plot.phase_function(table, wavelengths_nm=300)
    with pytest.raises(ValueError, match="wavelengths_nm must be one wavelength or a non-empty"):
        plot.phase_function(table, wavelengths_nm=[])
    with pytest.raises(ValueError, match="wavelengths_nm must be finite"):
        plot.phase_function(table, wavelengths_nm=[np.nan])


def test_functions_reject_what_is_not_a_table(table):
    with pytest.raises(TypeError, match="table must be a dustoptics.table.Table; got dict"):
        plot.phase_map({"phase": table.phase})


# ---------------------------------------------------------------- phase_map


def test_phase_map_mesh_is_the_tables_phase_on_a_log_norm(mpl, table):
    fig = plot.phase_map(table)
    assert isinstance(fig, mpl.figure.Figure)
    ax, cbar_ax = fig.axes
    assert "[deg]" in ax.get_xlabel()
    assert "[nm]" in ax.get_ylabel()
    assert "hg-test" in ax.get_title()
    assert "[sr" in cbar_ax.get_ylabel()
    (mesh,) = [c for c in ax.collections if isinstance(c, mpl.collections.QuadMesh)]
    values = np.ma.getdata(mesh.get_array()).reshape(table.phase.shape)
    np.testing.assert_array_equal(values, table.phase)
    assert isinstance(mesh.norm, mpl.colors.LogNorm)
    assert mesh.norm.vmin == table.phase.min()
    assert mesh.norm.vmax == table.phase.max()
    # Each grid point lies inside its own cell: rows are wavelengths, columns angles.
    corners = mesh.get_coordinates()  # (n_wavelength + 1, n_theta + 1, 2)
    x_edges, y_edges = corners[0, :, 0], corners[:, 0, 1]
    assert x_edges[0] == 0.0 and x_edges[-1] == 180.0
    assert np.all(x_edges[:-1] <= table.theta_deg) and np.all(table.theta_deg <= x_edges[1:])
    assert np.all(y_edges[:-1] < WAVELENGTH_NM) and np.all(y_edges[1:] > WAVELENGTH_NM)


def test_phase_map_single_wavelength(mpl, table):
    one = Table(
        name="one",
        wavelength_nm=[550.0],
        theta_deg=table.theta_deg,
        phase=table.phase[1:2],
        g=G[1:2],
    )
    fig = plot.phase_map(one)
    (mesh,) = [c for c in fig.axes[0].collections if isinstance(c, mpl.collections.QuadMesh)]
    np.testing.assert_array_equal(np.ma.getdata(mesh.get_array()).ravel(), one.phase.ravel())


# ---------------------------------------------------------------- spectra


def test_spectra_lines_are_cross_sections_albedo_and_g(mpl, table):
    fig = plot.spectra(table)
    assert isinstance(fig, mpl.figure.Figure)
    ax_c, ax_w, ax_g = fig.axes
    assert "hg-test" in ax_c.get_title()
    assert "[µm$^2$]" in ax_c.get_ylabel()
    assert "albedo" in ax_w.get_ylabel() and "[-]" in ax_w.get_ylabel()
    assert "g [-]" in ax_g.get_ylabel()
    assert "[nm]" in ax_g.get_xlabel()
    expected = {
        "extinction": CEXT_UM2,
        "scattering": CSCA_UM2,
        "absorption": CEXT_UM2 - CSCA_UM2,
    }
    lines = {line.get_label(): line for line in ax_c.get_lines()}
    assert set(lines) == set(expected)
    for label, values in expected.items():
        np.testing.assert_array_equal(lines[label].get_xdata(), WAVELENGTH_NM)
        np.testing.assert_allclose(lines[label].get_ydata(), values, rtol=1e-15)
    (albedo,) = ax_w.get_lines()
    np.testing.assert_allclose(albedo.get_ydata(), CSCA_UM2 / CEXT_UM2, rtol=1e-15)
    (g,) = ax_g.get_lines()
    np.testing.assert_array_equal(g.get_xdata(), WAVELENGTH_NM)
    np.testing.assert_array_equal(g.get_ydata(), G)


def test_spectra_of_a_phase_only_table_shows_g_and_says_so(mpl, phase_only):
    fig = plot.spectra(phase_only)
    (ax,) = fig.axes
    title = ax.get_title()
    assert "hg-phase-only" in title and "no cross-sections" in title
    assert "[nm]" in ax.get_xlabel() and "g [-]" in ax.get_ylabel()
    (line,) = ax.get_lines()
    np.testing.assert_array_equal(line.get_xdata(), WAVELENGTH_NM)
    np.testing.assert_array_equal(line.get_ydata(), G)


# ---------------------------------------------------------------- save


@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_save_is_valid_and_byte_identical(mpl, table, tmp_path, suffix):
    salt = mpl.rcParams["svg.hashsalt"]
    first = plot.save(plot.phase_function(table), tmp_path / f"a{suffix}")
    # A new figure of the same table, saved again: the same bytes.
    second = plot.save(plot.phase_function(table), tmp_path / f"b{suffix}")
    data = first.read_bytes()
    assert data == second.read_bytes()
    if suffix == ".png":
        assert data.startswith(PNG_SIGNATURE)
        assert b"Software" not in data
    else:
        root = ET.fromstring(data)
        assert root.tag == "{http://www.w3.org/2000/svg}svg"
        assert b"<dc:date>" not in data
    assert mpl.rcParams["svg.hashsalt"] == salt  # no global setting left changed
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        f"a{suffix}",
        f"b{suffix}",
    ]  # no temporaries


def test_save_map_and_spectra_reproducible_svg(mpl, table, phase_only, tmp_path):
    for name, make in [
        ("map", lambda: plot.phase_map(table)),
        ("spectra", lambda: plot.spectra(phase_only)),
    ]:
        a = plot.save(make(), tmp_path / f"{name}-1.svg").read_bytes()
        b = plot.save(make(), tmp_path / f"{name}-2.svg").read_bytes()
        assert a == b
        ET.fromstring(a)


def test_save_suffix_case_and_directories(mpl, table, tmp_path):
    path = plot.save(plot.spectra(table), tmp_path / "new" / "dir" / "S.PNG")
    assert path.read_bytes().startswith(PNG_SIGNATURE)


def test_save_refuses_to_overwrite_unless_asked(mpl, table, tmp_path):
    target = tmp_path / "fig.svg"
    target.write_bytes(b"old")
    fig = plot.spectra(table)
    with pytest.raises(FileExistsError, match="fig.svg already exist"):
        plot.save(fig, target)
    assert target.read_bytes() == b"old"
    plot.save(fig, target, overwrite=True)
    ET.fromstring(target.read_bytes())


@pytest.mark.parametrize("name", ["fig.pdf", "fig", "fig.png.txt"])
def test_save_unknown_suffix(table, tmp_path, name):
    # Checked before matplotlib is needed; the figure is not even looked at.
    with pytest.raises(ValueError, match=r"path must end in one of '\.png', '\.svg'; got '.*"):
        plot.save(object(), tmp_path / name)
    assert list(tmp_path.iterdir()) == []


def test_save_rejects_what_is_not_a_figure(mpl, tmp_path):
    with pytest.raises(TypeError, match="figure must be a matplotlib.figure.Figure; got str"):
        plot.save("fig", tmp_path / "fig.png")


# ---------------------------------------------------------------- optional dependency


def test_missing_matplotlib_names_the_extra(table, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # makes `import matplotlib` fail
    for call in (
        lambda: plot.phase_function(table),
        lambda: plot.phase_map(table),
        lambda: plot.spectra(table),
    ):
        with pytest.raises(ImportError, match=r"pip install 'dustoptics\[plot\]'"):
            call()


def test_package_imports_without_matplotlib_and_plotting_uses_no_pyplot(table):
    code = (
        "import sys\n"
        "sys.modules['matplotlib'] = None\n"
        "import dustoptics, dustoptics.plot\n"
        "del sys.modules['matplotlib']\n"
        "try:\n"
        "    import matplotlib\n"
        "except ImportError:\n"
        "    sys.exit(0)\n"
        "import io\n"
        "import numpy as np\n"
        "from dustoptics.table import Table\n"
        "t = Table(name='t', wavelength_nm=[500.0, 600.0], theta_deg=[0.0, 90.0, 180.0],\n"
        "          phase=np.full((2, 3), 1 / (4 * np.pi)), g=[0.0, 0.0])\n"
        "for f in (dustoptics.plot.phase_function(t), dustoptics.plot.phase_function(t, polar=True),\n"
        "          dustoptics.plot.phase_map(t), dustoptics.plot.spectra(t)):\n"
        "    f.savefig(io.BytesIO(), format='png')\n"
        "assert 'matplotlib.pyplot' not in sys.modules, 'pyplot was imported'\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], check=False, capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
