"""``python -m wrinkle``: the command line of ``wrinkle.cli``."""

import sys

from wrinkle.cli import main

__all__: list[str] = []

if __name__ == "__main__":
    sys.exit(main())
