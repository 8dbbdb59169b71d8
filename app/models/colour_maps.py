"""The explorer's continuous colour maps and fixed colours, read from shipped tables (Qt-free).

* density: ``viridis`` (perceptually uniform; lightness rises with density);
* hop distance: the future hemisphere dark and warm (:data:`FUTURE_CMAP`, near = darkest),
  the past one lighter and cool (:data:`PAST_CMAP`), each perceptually uniform; their
  lightness ranges do not overlap, and the greys of frames beyond the horizon
  (:data:`OUTSIDE_RGB`) and of unreachable frames (:data:`UNREACHABLE_RGB`) are lighter
  than both, so future, past and beyond stay apart in greyscale too;
* categories (phones, speakers, utterances, classes, landmarks) come from the session
  palette (:mod:`app.models.palette`), never from here.

The tables are written from matplotlib by :mod:`app.figures.colour_tables` (no matplotlib is
imported here); figures read the same names for the same meanings.
"""
from __future__ import annotations

import functools
import json
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Coloring", "DENSITY_CMAP", "FUTURE_CMAP", "PAST_CMAP", "UNREACHABLE_RGB", "OUTSIDE_RGB", "RESERVED_COLOURS",
           "LEGEND_MAX", "colour_table", "colormap_rgb", "map_values", "dim", "delta_e", "lightness", "limited_legend"]

#: frames with no value (unreachable state, no phone, no forward step)
UNREACHABLE_RGB = (0.82, 0.82, 0.82)
#: frames reachable but beyond the time horizon, or filtered out: near the background, so they recede
OUTSIDE_RGB = (0.92, 0.92, 0.92)
#: density: perceptually uniform, dark (sparse) to light (dense); no rainbow
DENSITY_CMAP = "viridis"
#: hop distance, near -> far within the horizon: the future a dark warm family, the past a lighter cool one
FUTURE_CMAP = "lipspace_future"
PAST_CMAP = "lipspace_past"
#: legends in the 3-D view list at most this many categories
LEGEND_MAX = 16

#: colours the manifold scene gives a meaning (app.scene.manifold and the view's markers); the legend names each
RESERVED_COLOURS = {
    "original trajectory": (0.0, 0.0, 0.0), "synthetic trajectory": (1.0, 0.0, 0.0),
    "state path": (1.0, 0.5, 0.0), "S": (0.0, 0.39, 0.0), "V": (0.545, 0.0, 0.545),
    "local s": (0.2, 0.75, 0.2), "local v": (0.85, 0.2, 0.85), "normal": (0.1, 0.45, 0.85),
    "selected": (1.0, 0.85, 0.0), "target": (0.0, 0.8, 0.8), "plane": (0.55, 0.55, 0.6),
    "axes": (0.35, 0.35, 0.35),
}

_TABLE_FILE = "colour_tables.json"  # package data of app.models


@functools.lru_cache(maxsize=1)
def _tables() -> dict:
    from importlib import resources

    return json.loads(resources.files("app.models").joinpath(_TABLE_FILE).read_text(encoding="utf-8"))


@functools.cache
def colour_table(name: str) -> np.ndarray:
    """RGB entries (n, 3) float64 of colour map ``name``, read from the shipped ``colour_tables.json``
    (written by :mod:`app.figures.colour_tables`; no matplotlib import here)."""
    tables = _tables()
    if name not in tables:
        raise KeyError(f"no colour table {name!r} in app/models/{_TABLE_FILE}; it has {', '.join(sorted(tables))}")
    table = np.asarray(tables[name], dtype=np.float64)
    table.setflags(write=False)
    return table


def colormap_rgb(name: str, t) -> np.ndarray:
    """Colours (..., 3) of ``t`` in [0, 1] on the 256-entry colour map ``name``, as matplotlib's
    ``colormaps[name](t)`` gives them (entry ``floor(t * 256)``, the last for t = 1)."""
    table = colour_table(name)
    n = table.shape[0]
    idx = np.clip((np.asarray(t, dtype=np.float64) * n).astype(np.int64), 0, n - 1)
    return table[idx]


def map_values(values, cmap: str, clim) -> np.ndarray:
    """``values`` (n,) through colour map ``cmap`` over ``clim``; non-finite values get :data:`UNREACHABLE_RGB`."""
    lo, hi = clim
    t = (np.asarray(values, dtype=np.float64) - lo) / (hi - lo if hi > lo else 1.0)
    rgb = colormap_rgb(cmap, np.clip(np.nan_to_num(t, nan=0.0), 0, 1))
    rgb[~np.isfinite(values)] = UNREACHABLE_RGB
    return rgb.astype(np.float32)


def lightness(rgb) -> np.ndarray:
    """CIELAB lightness L* (0 black .. 100 white) of sRGB colours (..., 3): what a greyscale print keeps."""
    from app.models.palette import srgb_to_lab

    return srgb_to_lab(np.asarray(rgb, dtype=np.float64))[..., 0]


def delta_e(a, b) -> np.ndarray:
    """CIE 1976 colour difference between sRGB colours ``a`` and ``b`` (broadcast)."""
    from app.models.palette import srgb_to_lab

    return np.linalg.norm(srgb_to_lab(np.asarray(a, float)) - srgb_to_lab(np.asarray(b, float)), axis=-1)


def limited_legend(entries, what: str) -> list:
    """At most :data:`LEGEND_MAX` legend rows, the last saying how many more there are."""
    if len(entries) <= LEGEND_MAX:
        return list(entries)
    return list(entries[:LEGEND_MAX]) + [(f"… {len(entries) - LEGEND_MAX} more ({what})", UNREACHABLE_RGB)]


def dim(rgb, amount: float = 0.7) -> np.ndarray:
    """Colours moved ``amount`` of the way towards :data:`OUTSIDE_RGB` (near the background)."""
    rgb = np.asarray(rgb, dtype=np.float32)
    return ((1 - amount) * rgb + amount * np.asarray(OUTSIDE_RGB, np.float32)).astype(np.float32)


@dataclass
class Coloring:
    """How to colour the manifold's points.

    Attributes
    ----------
    rgb : ndarray of shape (G, 3) float32 in [0, 1]
        One colour per drawn point (G = N while every frame is drawn).
    values : ndarray of shape (G,) float32 or None
        The scalar shown (density, signed hop distance), NaN = no value; None for categories.
    cmap : str, or ndarray of shape (n, 3) of RGB rows for a discrete scale, or None
    clim : (float, float) or None
    title : str
    legend : list of (str, (r, g, b))
        Category colours (class, phone, speaker, ...), and the greys of a scale's "no value".
    ticks : ndarray or None
        Values to label on the colour bar (whole hops for hop distance); None lets the bar choose.
    tick_labels : list of str or None
    readout : str
        One line for the status readout (e.g. the fraction inside the horizon).
    """

    rgb: np.ndarray
    values: np.ndarray | None = None
    cmap: object = None
    clim: tuple | None = None
    title: str = ""
    legend: list = field(default_factory=list)
    ticks: np.ndarray | None = None
    tick_labels: list | None = None
    readout: str = ""
