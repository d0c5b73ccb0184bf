"""``python -m tenscell.cli``: the same as ``tenscell`` (and ``python -m tenscell``)."""
import sys

from . import main

if __name__ == "__main__":
    sys.exit(main())
