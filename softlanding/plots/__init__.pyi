"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .paper import (
    plot_bang_bang, plot_controller_comparison, plot_cot_comparison, plot_depth_map,
    plot_depth_maps, plot_depth_vs_velocity, plot_experiment_curves, plot_gain_families,
    plot_optimal_curves, plot_robustness, plot_stepped_intrusion_figure, plot_stepped_intrusions,
    plot_trajectory
)
from .phased import (
    PHASE_COLOURS, plot_hop, plot_hybrid_findings, plot_phased_landing, plot_phases, shade_phases
)
from .terrain import plot_experiment_drag, plot_terrain_study
