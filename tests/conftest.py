"""Test configuration.

miepython is the independent reference for the brute-force accuracy tests.  Its
compiled kernels are off unless MIEPYTHON_USE_JIT=1 is set before its first
import (an import-time switch we fence rather than imitate: dustoptics never
reads it).  Setting it here, for the test process only, makes the reference
fast enough; it changes miepython's speed, not its results beyond round-off.
"""

import os

os.environ.setdefault("MIEPYTHON_USE_JIT", "1")
