"""Collection settings for the whole repository (``tests/`` and the package's doctests).

A module that moved leaves a shim at its old path (:func:`dustoptics._deprecated.alias_module`):
importing it gives the new module, so pytest's doctest collection would find the new module's
file behind the old path and stop with an "import file mismatch".  The shims hold no doctests
of their own; they are not collected (the moved module's doctests run at its new path).
"""

from __future__ import annotations

from pathlib import Path

_SHIM_CALL = "alias_module(__name__,"


def pytest_ignore_collect(collection_path: Path) -> bool | None:
    """Skip the shims at moved modules' old paths; leave every other decision to pytest."""
    if collection_path.suffix != ".py" or collection_path.name == "_deprecated.py":
        return None
    try:
        text = collection_path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    return True if _SHIM_CALL in text else None
