"""Plots (matplotlib, imported lazily; figures are built without pyplot, so no backend is switched).

:func:`save_figure` writes any figure as PNG (raster, ``dpi``) or as SVG or PDF (vector, text
kept as text: SVG ``<text>`` elements, TrueType fonts in PDF, as journals ask), chosen by the
file extension or ``format``.
"""

from __future__ import annotations

import os

FIGURE_FORMATS = ("png", "svg", "pdf")
"""Formats :func:`save_figure` writes."""

DPI = 200
"""Default resolution of raster (PNG) figures [dots per inch]."""

MAX_DPI = 1200
"""Highest resolution accepted: a 7 x 5 inch figure at 1200 dpi is 50 megapixels."""


def require_matplotlib():
    """Import matplotlib or raise an error naming the extra to install."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise ImportError("plotting needs matplotlib: pip install 'omnikin[viz]'") from None


def new_figure(**kwargs):
    """A ``matplotlib.figure.Figure`` with constrained layout (no pyplot, no backend switch)."""
    require_matplotlib()
    from matplotlib.figure import Figure

    return Figure(layout="constrained", **kwargs)


def check_dpi(dpi) -> float:
    """``dpi`` as a number in ``(0, MAX_DPI]``, else :class:`~omnikin.errors.InputError`."""
    from ..errors import InputError

    if isinstance(dpi, bool) or not isinstance(dpi, (int, float)) or not (0 < dpi <= MAX_DPI):
        raise InputError(f"dpi must be a number above 0 and at most {MAX_DPI}, got {dpi!r}")
    return float(dpi)


def figure_format(path, format: str | None = None) -> str:
    """The format of a figure file: ``format`` or the extension of ``path`` (one of :data:`FIGURE_FORMATS`)."""
    from ..errors import InputError

    fmt = (format or os.path.splitext(os.fspath(path))[1].lstrip(".")).lower()
    if fmt not in FIGURE_FORMATS:
        raise InputError(
            f"{os.fspath(path)}: figures are written as {', '.join(FIGURE_FORMATS)} "
            f"(chosen by the extension), not {fmt or 'a file without extension'!r}"
        )
    return fmt


def save_figure(fig, target, *, format: str | None = None, dpi: float = DPI) -> None:
    """Write ``fig`` to ``target`` (a path, or a binary file object with ``format``).

    PNG at ``dpi``; SVG with text as ``<text>`` elements and PDF with TrueType (type 42)
    fonts, so the text stays text in a paper's editor.
    """
    import matplotlib

    if format is None and not isinstance(target, (str, os.PathLike)):
        from ..errors import InputError

        raise InputError("save_figure: name the format of a figure written to a file object")
    fmt = figure_format(target if format is None else getattr(target, "name", "figure"), format)
    with matplotlib.rc_context({"svg.fonttype": "none", "pdf.fonttype": 42, "svg.hashsalt": "omnikin"}):
        fig.savefig(target, format=fmt, dpi=check_dpi(dpi), metadata=_metadata(fmt))


def _metadata(fmt: str) -> dict:
    """File metadata without a creation date, so the same figure gives the same bytes."""
    if fmt == "pdf":
        return {"CreationDate": None, "Creator": "omnikin"}
    if fmt == "svg":
        return {"Date": None, "Creator": "omnikin"}
    return {"Software": "omnikin"}
