"""``python -m dustoptics.cli``: the command line, as the ``dustoptics`` script runs it."""

import sys

from dustoptics.cli import main

sys.exit(main())
