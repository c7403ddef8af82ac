"""Access to the shared reference material beside the repository.

The project's tests cross-check against files in ``../shared`` (published
tables, benchmark values).  A user who clones the repository does not have
that directory; tests that need it are skipped with a message saying so.
"""

from __future__ import annotations

from pathlib import Path

import pytest

#: The shared directory: a sibling of the repository root.
SHARED_ROOT = Path(__file__).resolve().parents[1].parent / "shared"


def shared_path(*parts: str) -> Path:
    """Path of a file under ``../shared``, or skip the calling test if it is absent.

    Parameters
    ----------
    *parts : str
        Path components below the shared directory, e.g.
        ``("reference-data", "refractive-index", "ri_magnetite_querry1985.csv")``.

    Returns
    -------
    pathlib.Path
        The existing file or directory.
    """
    path = SHARED_ROOT.joinpath(*parts)
    if not path.exists():
        where = "directory" if not SHARED_ROOT.exists() else "file"
        pytest.skip(
            f"shared reference {where} not found: {path} (the ../shared directory beside the "
            f"repository is not present in this checkout; these cross-checks need it)"
        )
    return path
