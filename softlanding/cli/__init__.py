"""The ``softlanding`` console script: :func:`main`."""

from softlanding.cli.main import main

__all__ = ["main"]
