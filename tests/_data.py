"""The reference data the tests compare against, inside the repository (``tests/data/``).

Each file there says in its header what it holds, its citation, its licence and where its
numbers were read (``scripts/make_test_data.py`` writes them).  Nothing outside the repository
is needed: a missing file is an error, not a skip.
"""

from __future__ import annotations

from pathlib import Path

#: The folder of reference files.
DATA_ROOT = Path(__file__).resolve().parent / "data"


def data_path(*parts: str) -> Path:
    """Path of a reference file under ``tests/data``.

    Parameters
    ----------
    *parts : str
        Path components below ``tests/data``, e.g.
        ``("mie-benchmarks", "miev0_wiscombe_efficiencies.csv")``.

    Returns
    -------
    pathlib.Path
        The existing file.

    Raises
    ------
    FileNotFoundError
        The file is not there.
    """
    path = DATA_ROOT.joinpath(*parts)
    if not path.is_file():
        raise FileNotFoundError(f"reference file not found: {path}")
    return path


#: The seed thesis's Blue Moon's phase function table (Meyran 2022), in its own CSV layout
#: below a commented header: every 10th of its 1,800 angles and the last, all 48 wavelengths.
SEED_PHASE_EXCERPT = ("seed-tables", "MiePhaseFunctionSpectrum_excerpt.csv")
#: The indices of the excerpt's rows among the thesis's angles, linspace(0, 180, 1800).
SEED_ROWS = (*range(0, 1800, 10), 1799)
