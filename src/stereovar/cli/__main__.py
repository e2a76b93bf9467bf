# PYTHON_ARGCOMPLETE_OK
"""``python -m stereovar.cli``: the ``stereovar`` command."""

import sys

from . import main

if __name__ == "__main__":
    sys.exit(main())
