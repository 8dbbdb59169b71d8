"""The window's 3-D views (manifold, lips) as figures for a paper: PNG, SVG and PDF from one figure.

:func:`view_figure` redraws a view from its scene (:func:`app.figures.view_vector.scene_figure`)
at a journal width (:data:`app.figures.style.COLUMN_WIDTHS_MM`, or any width, or as on screen),
with the journal's text sizes; :func:`export_view` writes it. PNG, SVG and PDF are all written
from that figure, so they carry the same labels as the screen (the S and V labels, sensor
names, the legend and the colour bar), and the same widths as ``lipspace figures``.
"""
from __future__ import annotations

from pathlib import Path

__all__ = ["view_figure", "export_view", "VIEW_FORMATS", "DEFAULT_DPI"]

#: what a view is written as (by suffix)
VIEW_FORMATS = (".png", ".svg", ".pdf")
#: PNG resolution of a view written for print
DEFAULT_DPI = 300.0


def view_figure(plotter, *, width=None, title: str | None = None):
    """The view of ``plotter`` as a matplotlib figure ``width`` inches wide (None: as on screen).

    Reads the scene (VTK): call it in the thread that owns the view; writing the figure
    (:func:`app.figures.export.save_figure`) may then run in a worker.
    """
    from app.figures.style import WIDTH_RANGE_MM
    from app.figures.view_vector import scene_figure

    if width is not None:
        lo, hi = WIDTH_RANGE_MM
        if not lo / 25.4 - 1e-9 <= float(width) <= hi / 25.4 + 1e-9:
            raise ValueError(f"width {float(width) * 25.4:.0f} mm is outside {lo:g}-{hi:g} mm "
                             "(85 mm: one journal column, 180 mm: two)")
    return scene_figure(plotter, title=title, width=width)


def export_view(plotter, path, *, width=None, dpi: float = DEFAULT_DPI, title: str | None = None) -> Path:
    """Write the view of ``plotter`` to ``path`` (.png, .svg or .pdf by suffix), atomically: the figure of
    :func:`view_figure` (``width`` inches, None: as on screen), PNG at ``dpi``."""
    from app.figures.export import _suffix, save_figure

    _suffix(path, VIEW_FORMATS, "a view")
    return save_figure(view_figure(plotter, width=width, title=title), path, dpi=dpi)
