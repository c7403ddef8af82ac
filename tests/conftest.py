"""Test configuration.

miepython is the independent reference for the brute-force accuracy tests.  Its
compiled kernels are off unless MIEPYTHON_USE_JIT=1 is set before its first
import (an import-time switch we fence rather than imitate: dustoptics never
reads it).  Setting it here, for the test process only, makes the reference
fast enough; it changes miepython's speed, not its results beyond round-off.
"""

import os
import signal

os.environ.setdefault("MIEPYTHON_USE_JIT", "1")

# A shell's background job (`nohup ... &`) and pytest-xdist's workers start with Ctrl-C
# ignored, and a child inherits "ignored" through exec: the tests that send SIGINT to
# a command would see it ignored.  Python's own handler here resets the children's.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

from hypothesis import settings

# Property tests draw the same examples on every run (derandomized), so a
# suite that passed once passes again: CI never fails on a newly drawn case.
# Run `pytest --hypothesis-profile=explore` to search with fresh random cases.
settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile("deterministic")

# Run by Blender's own Python (``blender -b --python``), not by pytest: it imports ``bpy``.
collect_ignore = ["sky/blender_sphere.py"]
