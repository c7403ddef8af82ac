"""The sky's progress lines: at most 80 columns, the step and the time kept whole."""

from __future__ import annotations

import io
import re

import pytest

from dustoptics.sky import _progress
from dustoptics.sky._progress import COLUMNS, Reporter, fit_line


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.mark.parametrize("stream_type", [io.StringIO, _Terminal])
def test_progress_lines_fit_80_columns(monkeypatch: pytest.MonkeyPatch, stream_type) -> None:
    monkeypatch.setattr(_progress, "QUIET_SECONDS", 0.0)
    stream = stream_type()
    report = Reporter(stream, label="sky compare")
    text = "sky 13 of 24: model 4 of 4 (blue-moons), away from the Sun at 10 deg"
    report(text, last=True)
    report("orders of scattering: order 12, 40 of 64 Fourier modes still converging", last=True)
    lines = [ln.replace("\x1b[K", "") for ln in stream.getvalue().splitlines()]
    assert len(lines) == 2
    assert all(len(ln) <= COLUMNS == 80 for ln in lines), lines
    assert lines[0].startswith("sky compare: sky 13 of 24: model 4 of 4 (blue-moons), ")
    assert " ... " in lines[0] and re.search(r" 10 deg, \d+\.\d s$", lines[0])
    assert lines[1].startswith("sky compare: orders of scattering: order 12, ")


def test_fit_line_keeps_short_lines_and_cuts_one_long_word() -> None:
    assert (
        fit_line("sky: ", "lines of sight: 3 of 9", ", 1.0 s")
        == "sky: lines of sight: 3 of 9, 1.0 s"
    )
    line = fit_line("sky: ", "x" * 100, ", 1.0 s")
    assert len(line) == 80 and line.endswith("x..., 1.0 s")
