"""``python -m viapath.cli``: the ``viapath`` command."""

from viapath.cli import main

main()
