"""``python -m softlanding``: same as the ``softlanding`` command."""

from softlanding.cli.main import main

raise SystemExit(main())
