"""softlanding: optimal control of a two-mass legged robot landing on yielding terrain.

Implements and extends Lynch, Lynch & Umbanhowar, "The Soft Landing Problem:
Minimizing Energy Loss by a Legged Robot Impacting Yielding Terrain".

The value objects (:class:`Robot`, :class:`Impact`, the controllers
:class:`Rigid`, :class:`Impedance`, :class:`ForceSchedule`, and the ground
models) are validated once and passed to every study::

    from softlanding import PAPER_ROBOT, Impact, Impedance, simulate
    res = simulate(PAPER_ROBOT.without_force_limit(), Impact(-1), Impedance(0.2, 0.18))

The package's layers, each a subpackage with its own front door (dependencies run one way,
top to bottom):

* :mod:`softlanding.cli` -- the ``softlanding`` console script;
* :mod:`softlanding.report` -- the reproduction of the paper (:func:`reproduce`);
* :mod:`softlanding.studies` -- impedance optimisation, sweeps, comparison, robustness, terrain;
* :mod:`softlanding.optimal` -- optimal landings: the paper's, two-phase, leg extension, hopping;
  :mod:`softlanding.plots` beside it -- the figures;
* :mod:`softlanding.simulation` -- the exact event-driven simulator;
* :mod:`softlanding.model` -- robot, ground, terrain, controllers, dynamics, scaling;
* :mod:`ocp` (a separate package) -- generic optimal control problems with CasADi and Ipopt.

The names below are imported on first use, so a light command (``softlanding
--help``, a scale conversion) does not load CasADi or compile anything.
"""

import lazy_loader as _lazy

from softlanding._version import __version__ as __version__

__getattr__, __dir__, __all__ = _lazy.attach_stub(__name__, __file__)
