"""``python -m bgphm``: the same as the ``bgphm`` console script."""

import sys

from bgphm.cli import main

sys.exit(main())
