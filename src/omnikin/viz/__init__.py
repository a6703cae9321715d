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

MIN_DPI = 50
"""Lowest resolution accepted [dots per inch]: the coarsest screens a figure is looked at on (a
1080p television of 40 inches is 55 dpi; desktop screens are 90 to 220). Below it the figures'
smallest (7 pt) text is under 5 pixels high, a 6-inch figure shrinks to a thumbnail whose layout
collapses, and at a few dpi FreeType refuses to draw text at all."""

MAX_DPI = 1200
"""Highest resolution accepted [dots per inch]: what journals ask of line art (1000 to 1200 dpi;
photographs 300); a 7 x 5 inch figure at 1200 dpi is already 50 megapixels (200 MB in memory)."""


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


def dpi_problem(dpi) -> str | None:
    """None if ``dpi`` [dots per inch] is a real number in ``[MIN_DPI, MAX_DPI]`` (the range of
    screens and print), else what is wrong with it (``must lie in [50, 1200] dpi, got 1 ...``)."""
    from ..common.arrays import range_problem

    problem = range_problem(dpi, MIN_DPI, MAX_DPI, "dpi")
    return None if problem is None else f"{problem} (screens to print)"


def check_dpi(dpi, name: str = "dpi") -> float:
    """``dpi`` as a float if :func:`dpi_problem` finds nothing, else
    :class:`~omnikin.errors.InputError` naming ``name``. Checked before any work: by
    :meth:`omnikin.UMBmarkReport.write` before a figure is drawn, by ``omnikin umbmark --dpi``
    when the command line is read."""
    from ..errors import InputError

    problem = dpi_problem(dpi)
    if problem:
        raise InputError(f"{name} {problem}")
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
