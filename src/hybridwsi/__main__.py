"""``python -m hybridwsi``: the same as the ``hybridwsi`` console script."""

import sys

from hybridwsi.cli import main

if __name__ == "__main__":
    sys.exit(main())
