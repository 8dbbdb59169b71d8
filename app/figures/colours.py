"""The figures' colours: the window's colour maps and the session's categorical palette.

* Continuous quantities the window also shows use the window's maps
  (:data:`app.models.colouring.DENSITY_CMAP`, :data:`~app.models.colouring.FUTURE_CMAP`,
  :data:`~app.models.colouring.PAST_CMAP`), read by name here, so a figure and the view
  agree on what a colour means. Other continuous quantities (a displacement in mm) use
  :data:`MAGNITUDE_CMAP`, a perceptually uniform map.
* A sequential map's lightest end is cut where it would vanish on the white page
  (:data:`MAX_LIGHTNESS`), as the window cuts its hop maps.
* Every categorical colour (phones, landmarks, speakers, tangent classes, X and Y) comes
  from one :class:`app.models.palette.SessionPalette`: the figure functions take
  ``palette=None`` and fall back to the corpus's own (:func:`palette_for`), the palette the
  window builds for the same corpus.
* Colours with a fixed meaning in the window (original trajectory black, generated red,
  S and V) are :data:`app.models.colouring.RESERVED_COLOURS`.
"""
from __future__ import annotations

import functools

import numpy as np

__all__ = ["continuous_cmap", "density_cmap", "future_cmap", "past_cmap", "magnitude_cmap", "MAGNITUDE_CMAP",
           "MAX_LIGHTNESS", "palette_for", "reserved", "ORIGINAL", "GENERATED", "S_COLOUR", "V_COLOUR",
           "UNREACHABLE", "lightness"]

#: a perceptually uniform map for magnitudes no view shows (a displacement from the mean shape)
MAGNITUDE_CMAP = "cividis"
#: CIELAB lightness above which a sequential map's end is cut (too close to the white page)
MAX_LIGHTNESS = 90.0


def reserved(name: str) -> tuple:
    """The window's colour of a fixed meaning (:data:`app.models.colouring.RESERVED_COLOURS`) as (r, g, b)."""
    from app.models.colouring import RESERVED_COLOURS

    return tuple(float(c) for c in RESERVED_COLOURS[name])


ORIGINAL = reserved("original trajectory")
GENERATED = reserved("synthetic trajectory")
S_COLOUR = reserved("S")
V_COLOUR = reserved("V")


def _unreachable():
    from app.models.colouring import UNREACHABLE_RGB

    return tuple(float(c) for c in UNREACHABLE_RGB)


UNREACHABLE = _unreachable()


def lightness(rgb) -> np.ndarray:
    """CIELAB L* of sRGB colours (..., 3) in [0, 1]."""
    from app.models.palette import srgb_to_lab

    return srgb_to_lab(np.asarray(rgb, np.float64)[..., :3])[..., 0]


@functools.lru_cache(maxsize=None)
def continuous_cmap(name: str, *, trim_light: bool = True):
    """The matplotlib colour map called ``name`` (matplotlib's own, or a table of
    :func:`app.models.colouring.colour_table`), with its lightest end cut above
    :data:`MAX_LIGHTNESS` when ``trim_light`` (and the map runs from dark to light or back)."""
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap

    if name in colormaps:
        base = colormaps[name]
        rgb = base(np.linspace(0.0, 1.0, 256))[:, :3]
    else:
        from app.models.colouring import colour_table

        rgb = np.asarray(colour_table(name), np.float64)
    if trim_light:
        L = lightness(rgb)
        if L[-1] > MAX_LIGHTNESS and L[-1] >= L[0]:
            rgb = rgb[: max(2, int(np.argmax(L > MAX_LIGHTNESS)))]
        elif L[0] > MAX_LIGHTNESS and L[0] > L[-1]:
            rgb = rgb[int(np.argmax(L <= MAX_LIGHTNESS)):]
    return ListedColormap(rgb, name=f"lipspace:{name}")


def density_cmap():
    """The window's density map (low -> high)."""
    from app.models.colouring import DENSITY_CMAP

    return continuous_cmap(DENSITY_CMAP)


def future_cmap():
    """The window's future-hemisphere map (the seed's next states -> the farthest)."""
    from app.models.colouring import FUTURE_CMAP

    return continuous_cmap(FUTURE_CMAP)


def past_cmap():
    """The window's past-hemisphere map."""
    from app.models.colouring import PAST_CMAP

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
