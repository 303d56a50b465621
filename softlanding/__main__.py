"""``python -m softlanding``: same as the ``softlanding`` command."""

from softlanding.cli import main

raise SystemExit(main())
