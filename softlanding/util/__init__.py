"""Helpers shared by every layer: exclusive atomic output files, JSON-safe values, progress bars."""
