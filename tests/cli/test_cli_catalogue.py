"""``dustoptics presets`` and ``dustoptics materials``."""

from __future__ import annotations

import dustoptics as do
from dustoptics.cli import main
from dustoptics.models import presets


def test_presets_lists_names_and_shows_their_files(capsys):
    assert main(["presets"]) == 0
    out = capsys.readouterr().out
    for name in presets.list_presets():
        assert name in out
    assert "(default)" in out
    assert main(["presets", "--show", "hybrid"]) == 0
    assert capsys.readouterr().out == presets.preset_text("hybrid")
    assert main(["presets", "--show", "nope"]) == 2


def test_materials_lists_the_catalogue(capsys):
    assert main(["materials"]) == 0
    names = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert names == list(do.list_materials())
