"""``python -m softlanding``: same as the ``softlanding`` command."""

from softlanding.cli import console_main

try:
    code = console_main()
finally:
    # CPython marks a KeyboardInterrupt that arrived while a string exec or eval ran (a
    # dataclass or namedtuple being created at import, numba compiling) as unhandled even once
    # caught, and under ``-m`` then ends the process by SIGINT (status -2) after the run's own
    # report and exit code 130. A string exec clears the mark; an interruption that does escape
    # sets it again on its way out, as it should.
    exec("")
raise SystemExit(code)
