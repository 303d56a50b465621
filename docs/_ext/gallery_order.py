"""The gallery's order (sphinx-gallery imports it by name, so it lives in a module)."""


def gallery_order(filename: str) -> tuple[bool, str]:
    """The short plot_* examples first, in their numbered order; the worked variant last."""
    return (not filename.startswith("plot_"), filename)
