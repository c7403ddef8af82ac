"""``python -m dustoptics``: the command line, as the ``dustoptics`` script runs it."""

import sys

from dustoptics.cli import main

if __name__ == "__main__":  # not when imported (by the documentation's module scan)
    sys.exit(main())
