"""``python -m adaptive_dd.cli ARGS``: the ``adaptive-dd`` command."""

import sys

from adaptive_dd.cli import main

sys.exit(main())
