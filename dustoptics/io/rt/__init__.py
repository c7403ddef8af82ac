"""Plain-text files that radiative-transfer codes read.

- :mod:`~dustoptics.io.rt.disort`: DISORT's phase-function moments with
  extinction and single-scattering albedo (format ``disort``).
- libRadtran's ``aerosol_file explicit`` layer files (format ``libradtran``).

Both need ``compute_optics(expansion=...)``.
"""

from __future__ import annotations

from dustoptics.io.rt import disort
from dustoptics.io.rt.disort import (
    DISORT_SUFFIX,
    LIBRADTRAN_EXPLICIT_SUFFIX,
    LIBRADTRAN_LAYER_SUFFIX,
    disort_text,
    libradtran_texts,
    write_disort,
    write_libradtran,
)

__all__ = [
    "DISORT_SUFFIX",
    "LIBRADTRAN_EXPLICIT_SUFFIX",
    "LIBRADTRAN_LAYER_SUFFIX",
    "disort",
    "disort_text",
    "libradtran_texts",
    "write_disort",
    "write_libradtran",
]
