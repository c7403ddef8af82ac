"""Progress of the sky's longer computations, on a text stream.

A :class:`Reporter` is made once per user call (:func:`reporter`) and shared by
the steps it runs, so that every line carries the time since the call began.
Nothing is written during the first :data:`QUIET_SECONDS`: a sky that is
quick stays silent.  After that, a line at most every
:data:`INTERVAL_SECONDS` (on a terminal the line is rewritten in place) and
the last line of each step.
"""

from __future__ import annotations

import time
from typing import TextIO

__all__ = ["INTERVAL_SECONDS", "QUIET_SECONDS", "Reporter", "reporter"]

#: Silence at the start of a computation. [s]
QUIET_SECONDS = 2.0
#: Shortest time between two progress lines of one step. [s]
INTERVAL_SECONDS = 0.5


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
        line = f"{self.label}: {text}, {now:.1f} s"
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
