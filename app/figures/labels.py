"""Labels beside data points that never overlap each other, the points' markers or the drawn lines."""
from __future__ import annotations

import numpy as np

__all__ = ["place_labels", "line_segments"]

#: directions tried around a point, north-east first (degrees)
_ANGLES = np.radians([45, 135, -45, -135, 0, 180, 90, -90])


def line_segments(ax) -> np.ndarray:
    """Every segment of the lines drawn in data coordinates on ``ax``, in display coordinates: (S, 4) rows
    ``x0, y0, x1, y1`` (reference lines spanning the axes, such as ``axhline``, are left out)."""
    segs = []
    for line in ax.get_lines():
        if not line.get_visible() or line.get_transform() != ax.transData or line.get_linestyle() in ("None", "", " "):
            continue
        xy = np.asarray(line.get_xydata(), np.float64)
        if len(xy) < 2:
            continue
        d = ax.transData.transform(xy)
        ok = np.isfinite(d).all(axis=1)
        both = ok[:-1] & ok[1:]
        segs.append(np.hstack([d[:-1], d[1:]])[both])
    return np.concatenate(segs) if segs else np.zeros((0, 4))


def _crosses(box, segs) -> bool:
    """Whether any segment (S, 4) meets the rectangle ``box`` (a Bbox), by Liang-Barsky clipping."""
    if not len(segs):
        return False
    x0, y0, x1, y1 = segs.T
    dx, dy = x1 - x0, y1 - y0
    t0, t1 = np.zeros(len(segs)), np.ones(len(segs))
    for p, q in ((-dx, x0 - box.x0), (dx, box.x1 - x0), (-dy, y0 - box.y0), (dy, box.y1 - y0)):
        with np.errstate(divide="ignore", invalid="ignore"):
            r = q / p
        par = p == 0
        out = par & (q < 0)
        t0 = np.where(~par & (p < 0), np.maximum(t0, r), t0)
        t1 = np.where(~par & (p > 0), np.minimum(t1, r), t1)
        t0 = np.where(out, 2.0, t0)
    return bool(np.any(t0 <= t1))


def place_labels(ax, xy, labels, *, fontsize: float = 7.0, color="0.25", marker_pt: float = 7.0,
                 radii_pt=(4.0, 8.0, 13.0, 19.0), placed_texts=None, avoid_lines: bool = True) -> int:
    """Write ``labels`` beside the data points ``xy`` where nothing else is.

    Each label tries positions around its point (8 directions at growing distances,
    north-east first) and takes the first whose box overlaps no label placed before it,
    no other point's marker, no line drawn on the axes (``avoid_lines``) and stays inside
    the axes; failing that, the first that overlaps no label and no line and stays inside
    the axes, whatever marker it covers. A label with no such place is left out (never
    struck through by a line). Labels do not take part in the figure's layout, so the
    layout (and the places checked) stay as computed here. ``placed_texts``: a list that
    receives the annotations drawn.

    Parameters
    ----------
    ax : matplotlib Axes
    xy : ndarray of shape (n, 2), data coordinates
    labels : sequence of str, length n
    marker_pt : float
        Diameter of the points' markers in points (kept clear of labels).

    Returns
    -------
    int
        Number of labels left out.
    """
    from matplotlib.transforms import Bbox

    fig = ax.figure
    fig.draw_without_rendering()  # the final layout: positions below are in display units of it
    renderer = fig.canvas.get_renderer()
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    disp = ax.transData.transform(xy)
    half = 0.5 * marker_pt * fig.dpi / 72.0
    markers = [Bbox.from_extents(x - half, y - half, x + half, y + half) for x, y in disp]
    segs = line_segments(ax) if avoid_lines else np.zeros((0, 4))
    frame = ax.get_window_extent(renderer)
    pad = 0.6 * fig.dpi / 72.0  # half a point of air around each label
    placed, left_out = [], 0
    for k, ((x, y), lab) in enumerate(zip(xy, labels)):
        best = None
        for strict in (True, False):
            for r in radii_pt:
                for a in _ANGLES:
                    dx, dy = r * np.cos(a), r * np.sin(a)
                    ha = "left" if dx > 0.5 else "right" if dx < -0.5 else "center"
                    va = "bottom" if dy > 0.5 else "top" if dy < -0.5 else "center"
                    t = ax.annotate(str(lab), xy=(x, y), xytext=(dx, dy), textcoords="offset points", ha=ha,
                                    va=va, fontsize=fontsize, color=color, annotation_clip=False)
                    t.set_in_layout(False)
                    bb = t.get_window_extent(renderer)
                    bb = Bbox.from_extents(bb.x0 - pad, bb.y0 - pad, bb.x1 + pad, bb.y1 + pad)
                    free = (not any(bb.overlaps(o) for o in placed) and frame.contains(bb.x0, bb.y0)
                            and frame.contains(bb.x1, bb.y1) and not _crosses(bb, segs))
                    if strict:
                        free = free and not any(bb.overlaps(m) for j, m in enumerate(markers) if j != k)
                    if free:
                        best = (t, bb)
                        break
                    t.remove()
                if best:
                    break
            if best:
                break
        if best is None:
            left_out += 1
            continue
        placed.append(best[1])
        if placed_texts is not None:
            placed_texts.append(best[0])
    return left_out
