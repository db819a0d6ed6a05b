"""`python -m hil` runs the command-line interface."""

import sys

from hil.cli import main

sys.exit(main())
