"""Tests of ocp.structure."""
