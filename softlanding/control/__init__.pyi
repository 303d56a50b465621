from .estimation import GroundEstimate as GroundEstimate, GroundEstimator as GroundEstimator
from .mpc import DEFAULT_PERIOD as DEFAULT_PERIOD, MPCLanding as MPCLanding, mpc_landing as mpc_landing
from .plant import SteppingPlant as SteppingPlant
from .state_landing import STATE_PARAMETERS as STATE_PARAMETERS, state_landing_problem as state_landing_problem, state_parameters as state_parameters
