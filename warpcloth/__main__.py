"""``python -m warpcloth``: the ``warpcloth`` command."""

import sys

from .cli import main

sys.exit(main())
