"""Tests of ocp.definition."""
