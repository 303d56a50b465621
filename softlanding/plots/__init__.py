"""Figures with labelled axes, units and the paper's symbols: the paper's figures
(:mod:`.paper`), the phased landings' and hops' (:mod:`.phased`), the terrain study's
(:mod:`.terrain`), the landings on an unknown ground and their study's (:mod:`.control`).
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach_stub(__name__, __file__)
