"""``python -m mocks.ur CONFIG_JSON [SERVICE...]``: the simulator child process (see `mocks.ur.process`)."""

import sys

from mocks.ur.process import child_main

sys.exit(child_main())
