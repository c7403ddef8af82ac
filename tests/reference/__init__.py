"""Reference implementations that check the product and are not part of it.

Each is simple, independent of the code path it checks, and slower:

- :mod:`reference.derivatives`: polydisperse optics and their exact derivatives on a
  fixed, uniformly refined quadrature (``compute_optics(derivatives=...)`` is held
  against it);
- :mod:`reference.disort`: the sky's column solved by CDISORT (the ``test`` extra's
  nanodisort), the reference of the radiative transfer;
- :mod:`reference.mie`: plain-Python views of the Mie kernel's workspace and of its
  tiered angular sums, for the kernel's own tests.

The tests import them as ``reference.<module>`` (``tests/`` is on ``sys.path`` under
pytest); a script puts the repository root on ``sys.path`` and imports
``tests.reference.<module>``.
"""
