"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .comparison import compare_controllers as compare_controllers, comparison_arrays as comparison_arrays, rigid_depth as rigid_depth
from .impedance import GAIN_RANGE as GAIN_RANGE, ImpedanceOptimum as ImpedanceOptimum, OBJECTIVES as OBJECTIVES, optimize_impedance as optimize_impedance
from .robustness import CONTROLLERS as CONTROLLERS, PARAMETERS as PARAMETERS, design as design, replay as replay, robustness_study as robustness_study, robustness_table as robustness_table, transfer as transfer, true_model as true_model
from .sweeps import depth_map as depth_map, impedance_dataset as impedance_dataset, load_dataset as load_dataset, optimal_impedance_curves as optimal_impedance_curves, paper_observations as paper_observations, save_dataset as save_dataset
from .terrain_study import EXPERIMENT_FASTEST_V0 as EXPERIMENT_FASTEST_V0, STUDY_CD as STUDY_CD, bang_bang_rows as bang_bang_rows, experiment_curves as experiment_curves, experiment_grounds as experiment_grounds, experiment_shift as experiment_shift, model_rows as model_rows, study_grounds as study_grounds
from .unknown_ground import study_summary as study_summary, true_ground as true_ground, unknown_ground_case as unknown_ground_case, unknown_ground_study as unknown_ground_study
