"""``python -m tenscell``: the same as the ``tenscell`` command."""
import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
