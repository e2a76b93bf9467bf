# PYTHON_ARGCOMPLETE_OK
"""``python -m stereovar``: the ``stereovar`` command (:func:`stereovar.cli.main`)."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
