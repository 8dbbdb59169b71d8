"""The colour tables the explorer's Qt-free colouring reads, written from matplotlib's colour maps.

:mod:`app.models.colour_maps` must not import matplotlib (it runs in the window and in the
Qt-free state); it reads ``app/models/colour_tables.json``, which :func:`write_colour_tables`
makes and ``tests/app/models/test_colouring.py`` checks entry by entry. Every map is
perceptually uniform: ``viridis`` whole (density); for hop distance a stretch of ``inferno``
resampled to 256 entries (future: dark and warm) and a CIELAB ramp of one blue hue and chroma
with lightness rising in equal steps (past: lighter and cool), chosen so that their lightness
ranges do not overlap. :func:`colormap` gives any of them to matplotlib figures, so a figure
shows a meaning in the explorer's colours.
"""
from __future__ import annotations

import json
from pathlib import Path

from engine.files.atomic import atomic_write

__all__ = ["TABLES", "STRETCHES", "RAMPS", "OWN", "colour_tables", "write_colour_tables", "colormap", "TABLE_FILE",
           "lab_ramp"]

#: matplotlib colour maps shipped whole (256 entries each)
TABLES = ("viridis",)
#: maps made of a stretch of a matplotlib map: name -> (map, from, to), resampled to 256 entries
STRETCHES = {"lipspace_future": ("inferno", 0.16, 0.50)}
#: CIELAB ramps: name -> (L* from, L* to, hue in degrees, chroma), 256 entries of equal lightness steps
RAMPS = {"lipspace_past": (56.0, 76.0, 250.0, 32.0)}
#: the names the explorer made itself (not matplotlib's)
OWN = (*STRETCHES, *RAMPS)
TABLE_FILE = Path(__file__).resolve().parents[1] / "models" / "colour_tables.json"


def lab_ramp(L0: float, L1: float, hue: float, chroma: float, n: int = 256):
    """``n`` sRGB colours (n, 3) of one CIELAB hue and chroma, lightness from ``L0`` to ``L1`` in equal steps
    (D65; ValueError when a colour falls outside sRGB)."""
    import numpy as np

    L = np.linspace(L0, L1, n)
    fy = (L + 16) / 116
    fx = fy + chroma * np.cos(np.radians(hue)) / 500
    fz = fy - chroma * np.sin(np.radians(hue)) / 200
    d = 6 / 29

    def f(t):
        return np.where(t > d, t ** 3, 3 * d * d * (t - 4 / 29))

    xyz = np.stack([f(fx) * 0.95047, f(fy), f(fz) * 1.08883], -1)
    lin = xyz @ np.linalg.inv(np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722],
                                        [0.0193, 0.1192, 0.9505]])).T
    if lin.min() < -1e-6 or lin.max() > 1 + 1e-6:
        raise ValueError(f"CIELAB ramp L* {L0:g}-{L1:g}, hue {hue:g}, chroma {chroma:g} leaves the sRGB gamut")
    lin = np.clip(lin, 0.0, 1.0)
    return np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)


def _entries(name: str):
    import numpy as np
    from matplotlib import colormaps

    if name in STRETCHES:
        base, a, b = STRETCHES[name]
        return colormaps[base](np.linspace(a, b, 256))[:, :3]
    if name in RAMPS:
        return lab_ramp(*RAMPS[name])
    cm = colormaps[name]
    return cm(np.arange(cm.N))[:, :3]


def colour_tables() -> dict:
    """``{name: [[r, g, b], ...]}`` of :data:`TABLES`, :data:`STRETCHES` and :data:`RAMPS`."""
    return {name: [[round(float(v), 8) for v in row] for row in _entries(name)] for name in (*TABLES, *OWN)}


def colormap(name: str):
    """A matplotlib colour map for any name the explorer uses (its own maps included)."""
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap

    if name in OWN:
        return ListedColormap(_entries(name), name=name)
    return colormaps[name]


def write_colour_tables(path=TABLE_FILE) -> Path:
    """Write :func:`colour_tables` as JSON to ``path`` (atomically)."""
    path = Path(path)
    with atomic_write(path) as tmp:
        Path(tmp).write_text(json.dumps(colour_tables(), separators=(",", ":")) + "\n")
    return path


if __name__ == "__main__":
    print(f"wrote {write_colour_tables()}")
