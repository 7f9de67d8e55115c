"""``python -m pyrobots_aio.cli``: the ``pyrobots-aio`` command."""

import sys

from . import main

sys.exit(main())
