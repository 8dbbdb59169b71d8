"""The paper's figure set, rendered with matplotlib (Agg) from a fitted manifold.

Each figure is ``make_<name>(manifold, *, width=None, palette=None, **opts) ->
matplotlib.figure.Figure``, laid out for a journal width (:mod:`app.figures.style`) and coloured
with the session's palette (None: the corpus's own, :func:`app.figures.colours.palette_for`) and
the window's colour maps; the figure carries a ``lipspace`` dict attribute with the numbers it
shows (seed states, chosen utterance, errors...). :data:`FIGURES` maps names to functions in
paper order (the figure modules are imported when a figure or function is first asked for:
:data:`DESCRIPTIONS` alone imports no matplotlib); :func:`export_figure` renders one and saves it
atomically as PNG, SVG or PDF:
``lipspace figures`` and the window's File › Export figure both call it. The window's 3-D
views are written by :mod:`app.figures.view_export` (PNG, SVG and PDF from one figure of the
scene, :mod:`app.figures.view_vector`); :func:`save_plotter_image` (a screenshot at a DPI) and
:func:`save_plotter_vector` remain for scripts.

No pyplot: every figure owns an Agg canvas, so this works without a display and
never disturbs a Qt event loop.
"""
from __future__ import annotations

import importlib
import importlib.util
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the names below are imported on first use (see __getattr__)
    from collections.abc import Callable

    from app.figures.classes import make_classes
    from app.figures.clusters import make_fig4
    from app.figures.export import (
        FIGURE_FORMATS,
        VECTOR_3D_FORMATS,
        VectorExportUnavailable,
        save_figure,
        save_plotter_image,
        save_plotter_vector,
        vector_export_available,
    )
    from app.figures.hops import make_fig2b
    from app.figures.manifold import make_fig2a
    from app.figures.shape import make_fig1a, make_fig1b, make_fig2c, make_scree
    from app.figures.synthesis import make_fig3

__all__ = ["FIGURES", "DESCRIPTIONS", "UTTERANCE_FIGURES", "make_figure", "export_figure", "save_figure",
           "save_plotter_image", "save_plotter_vector", "vector_export_available", "VectorExportUnavailable",
           "FIGURE_FORMATS",
           "VECTOR_3D_FORMATS", "make_fig1a", "make_fig1b", "make_fig2a", "make_fig2b", "make_fig2c",
           "make_fig3", "make_fig4", "make_scree", "make_classes"]

#: name -> the module of this package that defines it, imported when the name is first read, so
#: that the window's menus (which need only the names and descriptions) import no matplotlib
_LAZY = {
    "make_classes": "classes", "make_fig4": "clusters", "make_fig2b": "hops", "make_fig2a": "manifold",
    "make_fig1a": "shape", "make_fig1b": "shape", "make_fig2c": "shape", "make_scree": "shape",
    "make_fig3": "synthesis",
    **dict.fromkeys(("FIGURE_FORMATS", "VECTOR_3D_FORMATS", "VectorExportUnavailable", "save_figure",
                     "save_plotter_image", "save_plotter_vector", "vector_export_available"), "export"),
}

#: name -> figure function, in the paper's order, extras last (the figure modules are imported
#: when it is first read)
FIGURES: dict[str, Callable[..., Any]]

#: figure name -> the name of its function, in the paper's order, extras last
_FUNCTIONS = {"fig1a": "make_fig1a", "fig1b": "make_fig1b", "fig2a": "make_fig2a", "fig2b": "make_fig2b",
              "fig2c": "make_fig2c", "fig3": "make_fig3", "fig4": "make_fig4", "scree": "make_scree",
              "classes": "make_classes"}


def __getattr__(name: str):
    """The figure functions, the export helpers, :data:`FIGURES` and the package's modules, imported on
    first use."""
    if name == "FIGURES":
        value: object = {fig: getattr(sys.modules[__name__], fn) for fig, fn in _FUNCTIONS.items()}
    elif name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    elif not name.startswith("__") and importlib.util.find_spec(f"{__name__}.{name}") is not None:
        return importlib.import_module(f"{__name__}.{name}")  # a module of the package (the import binds it)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))


#: name -> one-line description (menus, ``lipspace figures --help``)
DESCRIPTIONS = {
    "fig1a": "first two principal components of X as lip shapes, coloured by displacement",
    "fig1b": "residual variance vs number of components, X and Y",
    "fig2a": "the manifold in the first three dims of Y: density, S, V, s_i, v_i, a trajectory",
    "fig2b": "directed hop distances from an opening, a zero-velocity and a closing state",
    "fig2c": "lip shapes indexed by increasing S",
    "fig3": "an utterance's trajectory regenerated through its phone mid-points (red) vs original (black)",
    "fig4": "bilabial clusters /b/ /p/ /m/ with 2-s.d. ellipses and the zero-velocity plane",
    "scree": "scree of X and Y (per component and cumulative)",
    "classes": "proportions of the four tangent classes and where they lie",
}

#: figures that take ``utterance=`` (the GUI and the command line pass the chosen one)
UTTERANCE_FIGURES = ("fig2a", "fig3")


def make_figure(name: str, manifold, **opts):
    """Render figure ``name`` (a key of :data:`FIGURES`) from a fitted manifold."""
    if name not in _FUNCTIONS:
        raise ValueError(f"no figure {name!r}; choose from {', '.join(_FUNCTIONS)}")
    return getattr(sys.modules[__name__], _FUNCTIONS[name])(manifold, **opts)


def export_figure(name: str, manifold, path, *, dpi: float = 200, **opts) -> Path:
    """Render figure ``name`` and save it to ``path`` (.png/.svg/.pdf by suffix), atomically.

    ``opts`` go to the figure function. Returns the path written. The figure is
    rendered before the file is opened, so a failing figure never touches ``path``.
    """
    from app.figures.export import FIGURE_FORMATS, _suffix, save_figure

    _suffix(path, FIGURE_FORMATS, "a figure")
    fig = make_figure(name, manifold, **opts)
    return save_figure(fig, path, dpi=dpi)
