"""The model, defined once: the robot and the paper's constants (:mod:`.robot`), the ground
laws (:mod:`.ground`), granular-media terrain models (:mod:`.terrain`), the controllers
(:mod:`.controllers`), the hybrid dynamics every other layer derives from (:mod:`.dynamics`:
simulator, OCPs, PMP checks, impedance layer) and the scaling to physical units (:mod:`.scaling`).

Every name below is importable from here (``from softlanding.model import ...``),
loaded on first use.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submod_attrs={
        "controllers": [
            "Controller", "FeedbackSchedule", "ForceSchedule", "Impedance", "Rigid",
            "impedance_gains", "rigid_lock_gains"
        ],
        "dynamics": [
            "STATE_NAMES", "mechanical_energy", "mode_matrices", "robot_rhs", "stance_dynamics",
            "stance_functions", "yielding_ground_force"
        ],
        "ground": [
            "AddedMassGround", "CustomGround", "DragGround", "Ground", "LINEAR_GROUND",
            "LinearGround"
        ],
        "robot": [
            "G_EARTH", "Impact", "PAPER_IMPEDANCE_ROBOT", "PAPER_ROBOT", "Robot", "Units"
        ],
        "scaling": [
            "EXPERIMENT_KP", "EXPERIMENT_V0", "PhysicalParams", "Scenario", "paper_rig"
        ],
        "terrain": [
            "MEDIA", "Medium", "PAPER_FOOT_DIAMETER", "PAPER_K_G", "foot_area", "medium",
            "paper_rig_units", "poppy_seed_added_mass", "poppy_seed_drag", "power_law_ground",
            "rft_stiffness"
        ],
    },
)
