"""Tests of ocp.scenarios."""
