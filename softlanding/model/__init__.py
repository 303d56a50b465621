"""The model, defined once: the robot and the paper's constants (:mod:`.robot`), the ground
laws (:mod:`.ground`), granular-media terrain models (:mod:`.terrain`), the controllers
(:mod:`.controllers`), the hybrid dynamics every other layer derives from (:mod:`.dynamics`:
simulator, OCPs, PMP checks, impedance layer) and the scaling to physical units (:mod:`.scaling`).
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach_stub(__name__, __file__)
