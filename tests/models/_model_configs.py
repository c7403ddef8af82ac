"""Configuration texts shared by the tests of dustoptics.models (test_config, test_compute,
test_files)."""

from __future__ import annotations

#: A fast Mie configuration (small particles, few angles) for parsing and build tests.
SMALL = """\
name = "small"
description = "test dust"

[material]
model = "constant"
n = 1.5
k = 0.01

[size_distribution]
model = "modified_gamma"
r_eff_um = 0.2
v_eff = 0.1

[optics]
rtol = 1e-3
wavelengths_nm = { start = 400, stop = 490, step = 10 }
n_theta = 19
"""


def edit(text: str, old: str, new: str) -> str:
    """Replace ``old`` by ``new`` on the lines that start with ``old`` (key lines,
    not comments or strings), or else on the non-comment lines that contain it."""
    lines = text.splitlines(keepends=True)
    hits = [i for i, ln in enumerate(lines) if ln.startswith(old)]
    if not hits:
        hits = [
            i for i, ln in enumerate(lines) if old in ln and not ln.lstrip().startswith(("#", '"'))
        ]
    assert hits, old
    for i in hits:
        lines[i] = lines[i].replace(old, new, 1)
    return "".join(lines)
