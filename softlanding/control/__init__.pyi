from .commands import Command as Command
from .compiled import CompiledController as CompiledController
from .estimation import GroundEstimate as GroundEstimate, GroundEstimator as GroundEstimator
from .estimators import FilteredEstimator as FilteredEstimator, MeasuredEstimator as MeasuredEstimator, Reading as Reading
from .loop import LandingController as LandingController, LoopRecord as LoopRecord, LoopRun as LoopRun, run_loop as run_loop
from .mpc import CONTROLLERS as CONTROLLERS, DEFAULT_PERIOD as DEFAULT_PERIOD, mpc_landing as mpc_landing
from .plant import SteppingPlant as SteppingPlant
from .replan import ReplanController as ReplanController
from .result import MPCLanding as MPCLanding
from .robust import DEFAULT_BRANCH_TIME as DEFAULT_BRANCH_TIME, GroundLanding as GroundLanding, RobustLanding as RobustLanding, robust_landing as robust_landing, two_stage_landing as two_stage_landing
from .sensor import Sensor as Sensor
from .state_landing import STATE_PARAMETERS as STATE_PARAMETERS, plan_from_state as plan_from_state, solve_from_state as solve_from_state, state_landing_problem as state_landing_problem, state_parameters as state_parameters
