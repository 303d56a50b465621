"""Tests of ocp.certificate."""
