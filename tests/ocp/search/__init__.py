"""Tests of ocp.search."""
