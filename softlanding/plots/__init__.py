"""Figures: the paper's, the phased landings' and the terrain study's (matplotlib)."""
