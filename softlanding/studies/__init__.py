"""Studies built on the simulator and the optimal landings: impedance optimisation
(:mod:`.impedance`), impedance sweeps and datasets (:mod:`.sweeps`), the controller comparison
(:mod:`.comparison`), robustness to model error (:mod:`.robustness`) and the terrain study
(:mod:`.terrain_study`).

Every name below is importable from here (``from softlanding.studies import ...``),
loaded on first use.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submod_attrs={
        "comparison": [
            "compare_controllers", "comparison_arrays", "rigid_depth"
        ],
        "impedance": [
            "GAIN_RANGE", "ImpedanceOptimum", "OBJECTIVES", "optimize_impedance"
        ],
        "robustness": [
            "CONTROLLERS", "PARAMETERS", "design", "replay", "robustness_study", "robustness_table",
            "transfer", "true_model"
        ],
        "sweeps": [
            "depth_map", "impedance_dataset", "load_dataset", "optimal_impedance_curves",
            "paper_observations", "save_dataset"
        ],
        "terrain_study": [
            "EXPERIMENT_FASTEST_V0", "STUDY_CD", "bang_bang_rows", "experiment_curves",
            "experiment_grounds", "experiment_shift", "model_rows", "study_grounds"
        ],
    },
)
