"""The figures' colours: the window's colour maps and the session's categorical palette.

* Continuous quantities the window also shows use the window's maps
  (:data:`app.models.colour_maps.DENSITY_CMAP`, :data:`~app.models.colour_maps.FUTURE_CMAP`,
  :data:`~app.models.colour_maps.PAST_CMAP`), read by name here, so a figure and the view
  agree on what a colour means. Other continuous quantities (a displacement in mm) use
  :data:`MAGNITUDE_CMAP`, a perceptually uniform map.
* Every map is read through :func:`app.figures.colour_tables.colormap`, the function that
  writes the window's colour tables, so figure and window draw the same entries.
* Every categorical colour (phones, landmarks, speakers, tangent classes, X and Y) comes
  from one :class:`app.models.palette.SessionPalette`: the figure functions take
  ``palette=None`` and fall back to the corpus's own (:func:`palette_for`), the palette the
  window builds for the same corpus.
* Colours with a fixed meaning in the window (original trajectory black, generated red,
  S and V) are :data:`app.models.colour_maps.RESERVED_COLOURS`.
"""
from __future__ import annotations

import functools

from app.models.colour_maps import RESERVED_COLOURS, UNREACHABLE_RGB, lightness

__all__ = ["continuous_cmap", "density_cmap", "future_cmap", "past_cmap", "magnitude_cmap", "MAGNITUDE_CMAP",
           "palette_for", "reserved", "ORIGINAL", "GENERATED", "S_COLOUR", "V_COLOUR",
           "UNREACHABLE", "lightness"]

#: a perceptually uniform map for magnitudes no view shows (a displacement from the mean shape)
MAGNITUDE_CMAP = "cividis"


def reserved(name: str) -> tuple:
    """The window's colour of a fixed meaning (:data:`app.models.colour_maps.RESERVED_COLOURS`) as (r, g, b)."""
    return tuple(float(c) for c in RESERVED_COLOURS[name])


ORIGINAL = reserved("original trajectory")
GENERATED = reserved("synthetic trajectory")
S_COLOUR = reserved("S")
V_COLOUR = reserved("V")


UNREACHABLE = tuple(float(c) for c in UNREACHABLE_RGB)


@functools.cache
def continuous_cmap(name: str):
    """The matplotlib colour map the explorer calls ``name`` (:func:`app.figures.colour_tables.colormap`:
    matplotlib's own, or one of the explorer's maps), so a figure shows a meaning in the window's colours."""
    from app.figures.colour_tables import colormap

    return colormap(name)


def density_cmap():
    """The window's density map (low -> high)."""
    from app.models.colour_maps import DENSITY_CMAP

    return continuous_cmap(DENSITY_CMAP)


def future_cmap():
    """The window's future-hemisphere map (the seed's next states -> the farthest)."""
    from app.models.colour_maps import FUTURE_CMAP

    return continuous_cmap(FUTURE_CMAP)


def past_cmap():
    """The window's past-hemisphere map."""
    from app.models.colour_maps import PAST_CMAP

    return continuous_cmap(PAST_CMAP)


def magnitude_cmap():
    """:data:`MAGNITUDE_CMAP` (zero dark, the largest light)."""
    return continuous_cmap(MAGNITUDE_CMAP)


def palette_for(manifold, palette=None):
    """``palette``, or the corpus's own :class:`app.models.palette.SessionPalette` (what the window builds)."""
    if palette is not None:
        return palette
    from app.models.palette import SessionPalette

    return SessionPalette.for_corpus(manifold.corpus_)
