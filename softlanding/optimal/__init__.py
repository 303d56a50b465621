"""Optimal landings: the stance phases as ``ocp`` problems, the solve pipeline shared by every
variant, and one module per variant (the paper's single-phase landing, the two-phase landing,
leg extension, hopping)."""
