"""``python -m softlanding``: same as the ``softlanding`` command."""

from softlanding.cli import console_main

raise SystemExit(console_main())
