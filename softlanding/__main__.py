"""``python -m softlanding``: same as the ``softlanding`` command."""

from .cli import main

raise SystemExit(main())
