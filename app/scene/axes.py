"""The manifold view's named axes: Y1, Y2, Y3 along the cloud's box, each with the share of variance it holds.

F^y's first three dimensions are drawn as x, y, z. Three lines run from the cloud's
lower corner along its box, each labelled at its far end with its name and the share of
the embedding's variance it holds (``embedding_.explained_variance_ratio_``). The embedding's
coordinates have no physical unit (they keep the distances of shape and scaled velocity),
so no numbers are written on the lines.
"""
from __future__ import annotations

import numpy as np
import pyvista as pv

from app.models.colour_maps import RESERVED_COLOURS
from app.scene.handles import Handle

__all__ = ["add_embedding_axes", "axis_labels", "AXIS_COLOUR"]

AXIS_COLOUR = RESERVED_COLOURS["axes"]
#: font size (pixels) of the axis names
AXIS_LABEL_PX = 12


def axis_labels(shares) -> list[str]:
    """``["Y1 · 41% of variance", ...]`` for the first three dimensions' shares (fractions; None: unknown)."""
    out = []
    for j in range(3):
        share = None if shares is None or j >= len(shares) else shares[j]
        known = share is not None and np.isfinite(share)
        out.append(f"Y{j + 1}" + (f" · {100 * share:.0f}% of variance" if known else ""))
    return out


def add_embedding_axes(plotter, bounds, labels, *, pad: float = 0.04, name: str = "embedding_axes") -> dict:
    """Axis lines along the box ``bounds`` (xmin, xmax, ymin, ymax, zmin, zmax) from its lower corner, named.

    Returns ``{"lines": Handle, "labels": actor, "tips": (3, 3) label positions, "names": the labels}``;
    nothing is rendered.
    """
    lo, hi = np.reshape(np.asarray(bounds, dtype=np.float64), (3, 2)).T
    ext = np.maximum(hi - lo, 1e-12)
    origin = lo - pad * ext  # just outside the cloud, so the lines are not buried in it
    ends = np.array([origin + np.eye(3)[j] * (hi[j] - origin[j]) for j in range(3)])
    pts = np.vstack([origin, ends])
    lines = np.hstack([[2, 0, j + 1] for j in range(3)])
    mesh = pv.PolyData(pts, lines=lines)
    actor = plotter.add_mesh(mesh, color=AXIS_COLOUR, line_width=1.5, name=name, pickable=False, reset_camera=False,
                             render=False)
    tips = origin + (ends - origin) * 1.04
    names = plotter.add_point_labels(tips, list(labels), font_size=AXIS_LABEL_PX, text_color=AXIS_COLOUR,
                                     shape=None, show_points=False, name=f"{name}_labels", always_visible=True,
                                     pickable=False, reset_camera=False, render=False)
    return {"lines": Handle(plotter, mesh, actor), "labels": names, "tips": tips, "names": list(labels)}
