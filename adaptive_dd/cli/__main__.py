"""``python -m adaptive_dd.cli ARGS``: the ``adaptive-dd`` command."""

from adaptive_dd.cli import console

console()
