"""Studies built on the simulator and the optimal landings: impedance optimisation
(:mod:`.impedance`), impedance sweeps and datasets (:mod:`.sweeps`), the controller comparison
(:mod:`.comparison`), robustness to model error (:mod:`.robustness`) and the terrain study
(:mod:`.terrain_study`).
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach_stub(__name__, __file__)
