"""``python -m softlanding``: same as the ``softlanding`` command."""

from softlanding.cli import console_main

code = console_main()
# CPython marks a KeyboardInterrupt that ended a string exec or eval (code a library generated
# with exec: a dataclass's methods, numba's) as unhandled even when it was caught, and under
# ``-m`` then ends the process by SIGINT (status -2) after the run's own one-line report and
# exit code 130; each string exec clears that mark (the console script is not affected).
exec("")
raise SystemExit(code)
