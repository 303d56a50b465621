"""Studies built on the simulator and the optimal landings: impedance optimisation, sweeps,
controller comparison, robustness, the terrain study."""
