"""ocp: generic multiple-shooting optimal control on CasADi and Ipopt.

Knows nothing of landing. The transcription, solution and switching-time
refinement modules are being built (see the project's issue tracker); this
package exists now so that the installed layout is stable.
"""

__all__: list[str] = []
