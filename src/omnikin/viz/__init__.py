"""Plots (matplotlib, imported lazily; figures are built without pyplot, so no backend is switched)."""


def require_matplotlib():
    """Import matplotlib or raise an error naming the extra to install."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise ImportError("plotting needs matplotlib: pip install 'omnikin[viz]'") from None
