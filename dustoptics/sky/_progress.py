"""Progress of the sky's longer computations, on a text stream.

A :class:`Reporter` is made once per user call (:func:`reporter`) and shared by
the steps it runs, so that every line carries the time since the call began.
Nothing is written during the first :data:`QUIET_SECONDS`: a sky that is
quick stays silent.  After that, a line at most every
:data:`INTERVAL_SECONDS` (on a terminal the line is rewritten in place) and
the last line of each step.  A line is at most :data:`COLUMNS` characters
wide (:func:`fit_line`), so that it does not wrap in an 80-column terminal.
"""

from __future__ import annotations

import time
from typing import TextIO

__all__ = ["COLUMNS", "INTERVAL_SECONDS", "QUIET_SECONDS", "Reporter", "fit_line", "reporter"]

#: Silence at the start of a computation. [s]
QUIET_SECONDS = 2.0
#: Shortest time between two progress lines of one step. [s]
INTERVAL_SECONDS = 0.5
#: Widest progress line, in characters (a terminal's default width).
COLUMNS = 80


def fit_line(head: str, text: str, tail: str, *, width: int = COLUMNS) -> str:
    """``head + text + tail``, ``text`` shortened to fit ``width`` characters.

    The head (what is reported on) and the tail (the time) are kept whole; so
    are the text's first words (the step, k of n) and its last ones (the
    values), the words between them give way to ``"..."``.

    >>> fit_line("sky: ", "orders of scattering: order 12, 40 of 64 Fourier modes still "
    ...          "converging", ", 1234.5 s", width=60)
    'sky: orders of scattering: ... still converging, 1234.5 s'
    """
    room = width - len(head) - len(tail)
    if len(text) <= room:
        return head + text + tail
    words = text.split(" ")
    left, right = 0, len(words)  # keep words[:left] and words[right:]

    def shortened(n_left: int, n_right: int) -> str:
        return " ".join([*words[:n_left], "...", *words[n_right:]])

    # The last two words (a value and its unit) first, then the first words, then the last.
    if len(words) > 2 and len(shortened(0, len(words) - 2)) <= room:
        right = len(words) - 2
    while left < right and len(shortened(left + 1, right)) <= room:
        left += 1
    while left < right and len(shortened(left, right - 1)) <= room:
        right -= 1
    if left == 0 and right == len(words):  # not even one word fits
        return head + text[: max(0, room - 3)] + "..." + tail
    return head + shortened(left, right) + tail


class Reporter:
    """Writes ``"sky: <text>, <elapsed> s"`` lines to a stream (or nowhere).

    Parameters
    ----------
    stream : text stream or None
        Where to write (None: silent).
    label : str
        Prefix of every line.
    """

    def __init__(self, stream: TextIO | None, *, label: str = "sky") -> None:
        if stream is not None and not callable(getattr(stream, "write", None)):
            raise TypeError(
                f"progress must be a text stream (e.g. sys.stderr) or None; got {stream!r}"
            )
        self.stream = stream
        self.label = label
        self.start = time.perf_counter()
        self._last = -1.0
        self._pending = False
        self._tty = bool(stream is not None and getattr(stream, "isatty", lambda: False)())

    @property
    def elapsed(self) -> float:
        """Seconds since the computation began. [s]"""
        return time.perf_counter() - self.start

    def __call__(self, text: str, *, last: bool = False) -> None:
        """Report ``text``; ``last`` marks the final line of a step."""
        if self.stream is None:
            return
        now = self.elapsed
        if now < QUIET_SECONDS:
            return
        if not last and now - self._last < INTERVAL_SECONDS:
            return
        self._last = now
        line = fit_line(f"{self.label}: ", text, f", {now:.1f} s")
        if self._tty and not last:
            self.stream.write("\r" + line + "\x1b[K")
            self._pending = True
        else:
            self.stream.write(
                ("\r" if self._pending else "") + line + ("\x1b[K" if self._tty else "") + "\n"
            )
            self._pending = False
        self.stream.flush()


def reporter(progress: TextIO | Reporter | None, *, label: str = "sky") -> Reporter:
    """The caller's reporter, or a new one writing to ``progress``."""
    if isinstance(progress, Reporter):
        return progress
    return Reporter(progress, label=label)
