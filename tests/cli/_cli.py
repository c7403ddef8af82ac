"""What the command-line tests share: a small configuration and a quiet build of it.

Most builds use this configuration (three wavelengths, 19 angles, rtol 1e-3: well
under a second); a few build a shipped preset.
"""

from __future__ import annotations

import pytest

from dustoptics.cli import main

SMALL = """\
name = "small-dust"
description = "three wavelengths of Blue Moon's dust, for the command-line tests"

[material]
model = "mars_dust"
hematite_fraction = 0.03
host_index = { n = 1.5, k = 0.0 }
hematite = "querry-extraordinary"
rule = "maxwell_garnett"

[size_distribution]
model = "modified_gamma"
r_eff_um = 1.0
v_eff = 0.2

[optics]
weighting = "scattering"
rtol = 1e-3
wavelengths_nm = [440.0, 550.0, 680.0]
n_theta = 19

[phase]
model = "mie"
"""


@pytest.fixture(name="config")
def config_fixture(tmp_path):
    """``config``: the small configuration (:data:`SMALL`) as a TOML file (a test module
    imports ``config_fixture`` to use it)."""
    path = tmp_path / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return path


def run_build(config, out, *extra: str) -> int:
    """``dustoptics build CONFIG --out OUT --quiet EXTRA...``; the exit status."""
    return main(["build", str(config), "--out", str(out), "--quiet", *extra])
