"""Plain-text files that radiative-transfer codes read.

- :mod:`~dustoptics.io.rt.disort`: DISORT's phase-function moments with
  extinction and single-scattering albedo (format ``disort``).
- :mod:`~dustoptics.io.rt.libradtran`: libRadtran's ``aerosol_file explicit``
  list and layer file (format ``libradtran``), with the same moments.

Both need ``compute_optics(expansion=...)``.
"""

from __future__ import annotations

from dustoptics.io.rt import disort, libradtran
from dustoptics.io.rt.disort import DISORT_SUFFIX, disort_text, write_disort
from dustoptics.io.rt.libradtran import (
    LIBRADTRAN_EXPLICIT_SUFFIX,
    LIBRADTRAN_LAYER_SUFFIX,
    libradtran_texts,
    write_libradtran,
)

__all__ = [
    "DISORT_SUFFIX",
    "LIBRADTRAN_EXPLICIT_SUFFIX",
    "LIBRADTRAN_LAYER_SUFFIX",
    "disort",
    "disort_text",
    "libradtran",
    "libradtran_texts",
    "write_disort",
    "write_libradtran",
]
