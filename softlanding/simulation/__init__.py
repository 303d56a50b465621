"""Exact event-driven simulation of a landing: the simulator, the ground laws compiled for the
kernel, the actuator's work, and the compiled kernel itself
(:mod:`softlanding.simulation.kernel`)."""
