"""``python -m omnikin.runtime.protocol``: the generators' command line (:mod:`.cli`)."""

import sys

from .cli import main

sys.exit(main())
