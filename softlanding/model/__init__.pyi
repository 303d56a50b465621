"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .controllers import Controller as Controller, FeedbackSchedule as FeedbackSchedule, ForceSchedule as ForceSchedule, Impedance as Impedance, Rigid as Rigid, impedance_gains as impedance_gains, rigid_lock_gains as rigid_lock_gains
from .dynamics import STATE_NAMES as STATE_NAMES, mechanical_energy as mechanical_energy, mode_matrices as mode_matrices, robot_rhs as robot_rhs, stance_dynamics as stance_dynamics, stance_functions as stance_functions, yielding_ground_force as yielding_ground_force
from .ground import AddedMassGround as AddedMassGround, CustomGround as CustomGround, DragGround as DragGround, Ground as Ground, LINEAR_GROUND as LINEAR_GROUND, LinearGround as LinearGround, linear_or_drag as linear_or_drag
from .robot import G_EARTH as G_EARTH, Impact as Impact, PAPER_IMPEDANCE_ROBOT as PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT as PAPER_ROBOT, Robot as Robot, Units as Units
from .scaling import EXPERIMENT_KP as EXPERIMENT_KP, EXPERIMENT_V0 as EXPERIMENT_V0, PhysicalParams as PhysicalParams, Scenario as Scenario, paper_rig as paper_rig
from .terrain import MEDIA as MEDIA, Medium as Medium, PAPER_FOOT_DIAMETER as PAPER_FOOT_DIAMETER, PAPER_K_G as PAPER_K_G, foot_area as foot_area, medium as medium, paper_rig_units as paper_rig_units, poppy_seed_added_mass as poppy_seed_added_mass, poppy_seed_drag as poppy_seed_drag, power_law_ground as power_law_ground, rft_stiffness as rft_stiffness
