"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .controllers import (
    Controller, FeedbackSchedule, ForceSchedule, Impedance, Rigid, impedance_gains, rigid_lock_gains
)
from .dynamics import (
    STATE_NAMES, mechanical_energy, mode_matrices, robot_rhs, stance_dynamics, stance_functions,
    yielding_ground_force
)
from .ground import AddedMassGround, CustomGround, DragGround, Ground, LINEAR_GROUND, LinearGround
from .robot import G_EARTH, Impact, PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT, Robot, Units
from .scaling import EXPERIMENT_KP, EXPERIMENT_V0, PhysicalParams, Scenario, paper_rig
from .terrain import (
    MEDIA, Medium, PAPER_FOOT_DIAMETER, PAPER_K_G, foot_area, medium, paper_rig_units,
    poppy_seed_added_mass, poppy_seed_drag, power_law_ground, rft_stiffness
)
