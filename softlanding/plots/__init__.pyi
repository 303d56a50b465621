"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .control import plot_mpc_landing as plot_mpc_landing, plot_robust_landing as plot_robust_landing, plot_unknown_ground_study as plot_unknown_ground_study
from .paper import plot_bang_bang as plot_bang_bang, plot_controller_comparison as plot_controller_comparison, plot_cot_comparison as plot_cot_comparison, plot_depth_map as plot_depth_map, plot_depth_maps as plot_depth_maps, plot_depth_vs_velocity as plot_depth_vs_velocity, plot_experiment_curves as plot_experiment_curves, plot_gain_families as plot_gain_families, plot_optimal_curves as plot_optimal_curves, plot_robustness as plot_robustness, plot_stepped_intrusion_figure as plot_stepped_intrusion_figure, plot_stepped_intrusions as plot_stepped_intrusions, plot_trajectory as plot_trajectory
from .phased import PHASE_COLOURS as PHASE_COLOURS, plot_hop as plot_hop, plot_hybrid_findings as plot_hybrid_findings, plot_phased_landing as plot_phased_landing, plot_phases as plot_phases, shade_phases as shade_phases
from .terrain import plot_experiment_drag as plot_experiment_drag, plot_terrain_study as plot_terrain_study
