"""``python -m fruitimpact``: the same as the ``fruitimpact`` console script."""

import sys

from fruitimpact.cli import main

sys.exit(main(sys.argv[1:]))
