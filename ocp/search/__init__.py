"""Many starts: the distinct local optima of a problem and the best (:func:`~ocp.multistart`)."""
