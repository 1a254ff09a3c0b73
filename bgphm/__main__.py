"""``python -m bgphm``: the same as the ``bgphm`` console script."""

import sys

from bgphm.cli import main

__all__: list[str] = []  # a script: nothing to import from it

if __name__ == "__main__":
    sys.exit(main())
