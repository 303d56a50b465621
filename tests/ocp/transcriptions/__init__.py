"""Tests of ocp.transcriptions."""
