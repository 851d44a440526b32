"""``python -m fruitimpact``: the same as the ``fruitimpact`` console script (its Ctrl-C and numba start-up)."""

import sys

from fruitimpact.cli import main

sys.exit(main())
