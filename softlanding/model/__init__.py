"""The model: the robot and the paper's constants, impacts, ground and terrain laws, controllers,
the hybrid dynamics (one definition, used by the simulator, the OCPs, the PMP checks and the
impedance layer) and the scaling to physical units."""
