"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .comparison import compare_controllers, comparison_arrays, rigid_depth
from .impedance import GAIN_RANGE, ImpedanceOptimum, OBJECTIVES, optimize_impedance
from .robustness import (
    CONTROLLERS, PARAMETERS, design, replay, robustness_study, robustness_table, transfer,
    true_model
)
from .sweeps import (
    depth_map, impedance_dataset, load_dataset, optimal_impedance_curves, paper_observations,
    save_dataset
)
from .terrain_study import (
    EXPERIMENT_FASTEST_V0, STUDY_CD, bang_bang_rows, experiment_curves, experiment_grounds,
    experiment_shift, model_rows, study_grounds
)
