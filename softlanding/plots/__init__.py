"""Figures with labelled axes, units and the paper's symbols: the paper's figures
(:mod:`.paper`), the phased landings' and hops' (:mod:`.phased`), the terrain study's
(:mod:`.terrain`).

Every name below is importable from here (``from softlanding.plots import ...``),
loaded on first use.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submod_attrs={
        "paper": [
            "plot_bang_bang", "plot_controller_comparison", "plot_cot_comparison", "plot_depth_map",
            "plot_depth_maps", "plot_depth_vs_velocity", "plot_experiment_curves",
            "plot_gain_families", "plot_optimal_curves", "plot_robustness",
            "plot_stepped_intrusion_figure", "plot_stepped_intrusions", "plot_trajectory"
        ],
        "phased": [
            "PHASE_COLOURS", "plot_hop", "plot_hybrid_findings", "plot_phased_landing",
            "plot_phases",
            "shade_phases"
        ],
        "terrain": [
            "plot_experiment_drag", "plot_terrain_study"
        ],
    },
)
