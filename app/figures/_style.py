"""Shared drawing helpers for the paper's figures (matplotlib, Agg, no pyplot).

Every figure is a :class:`matplotlib.figure.Figure` with its own
:class:`~matplotlib.backends.backend_agg.FigureCanvasAgg`, so nothing touches
pyplot's global state and no display is needed. Colours follow the paper:
blue = low / far / sparse, red = high / near / dense (matplotlib's ``jet``).
"""
from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.colors import Normalize, to_rgba
from matplotlib.figure import Figure

#: colour map of the paper's figures: blue (low) -> red (high)
CMAP = colormaps["jet"]
#: reversed: red (near) -> blue (far), for geodesic distances
CMAP_NEAR = colormaps["jet_r"]
#: unreachable states in distance plots
UNREACHABLE = "#b0b0b0"
#: original trajectories are black, generated ones red (paper figs 2a, 3)
ORIGINAL = "black"
GENERATED = "red"
#: global / local shape and velocity directions
S_COLOUR = "#006400"   # dark green
V_COLOUR = "#8b008b"   # dark magenta
#: the four tangent classes (engine.tangent.TangentFrames.classes_ 0..3)
CLASS_COLOURS = ("#d62728", "#ff9896", "#1f4fb4", "#8fb8ff")

#: above this many points, large scatters are rasterised inside SVG/PDF
RASTERIZE_ABOVE = 4000


def new_figure(width: float, height: float, **kw) -> Figure:
    """A Figure of ``width`` x ``height`` inches with an Agg canvas attached."""
    fig = Figure(figsize=(width, height), layout="constrained", **kw)
    FigureCanvasAgg(fig)
    fig.lipspace = {}
    return fig


def require_fitted(manifold, *attrs):
    """Raise a clear error unless ``manifold`` is a fitted Manifold with ``attrs``."""
    missing = [a for a in ("Fy_", *attrs) if getattr(manifold, a, None) is None]
    if missing:
        raise ValueError(f"figures need a fitted engine.manifold.Manifold (missing {', '.join(missing)}); "
                         "fit one with Manifold().fit(corpus) or load one with Manifold.load(path)")


def below(ax, text, *, fontsize=7.5):
    """A note under an axes' x label, inside the constrained layout (never overlapping)."""
    # anchored under the x label itself (wherever the layout puts it), not at a fixed offset that a
    # tall tick label or x label can reach
    t = ax.annotate(text, xy=(0.5, 0.0), xycoords=ax.xaxis.label, xytext=(0, -3), textcoords="offset points",
                    va="top", ha="center", fontsize=fontsize, color="0.25", annotation_clip=False)
    t.set_gid("note")
    return t


def rasterize_for(n: int) -> bool:
    return n > RASTERIZE_ABOVE


def marker_size(n: int, *, big: float = 12.0, small: float = 1.0) -> float:
    """Scatter marker area that keeps ``n`` points readable on a small panel."""
    return float(np.clip(4000.0 / max(n, 1), small, big))


# ---------------------------------------------------------------- Y coordinates
def y3(manifold) -> np.ndarray:
    """First three dims of F^y as float64, (N, 3) (padded with zeros if Y has fewer)."""
    Fy = np.asarray(manifold.Fy_, dtype=np.float64)
    if Fy.shape[1] >= 3:
        return Fy[:, :3]
    return np.hstack([Fy, np.zeros((Fy.shape[0], 3 - Fy.shape[1]))])


def sv_basis(tangent) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(origin (3,), S (3,), V (3,)): the global shape and velocity directions
    (:meth:`engine.tangent.TangentFrames.sv_basis`)."""
    return tangent.sv_basis()


def sv_coords(Y, tangent) -> np.ndarray:
    """Coordinates of points ``Y`` (n, 3) along (S, V) about the plane point, (n, 2)
    (:meth:`engine.tangent.TangentFrames.sv_coordinates`, which the frame table uses too)."""
    return tangent.sv_coordinates(Y)


def plane_trace(ax, tangent, axes, Y, **kw):
    """Dotted trace of the zero-velocity plane on a panel showing Y axes ``axes``.

    The trace is the plane's intersection with the panel's coordinate plane through
    ``plane_point_`` (the third coordinate held at the plane point). Returns the
    Line2D or None when the plane is parallel to the panel.
    """
    a, b = axes
    n = np.asarray(tangent.plane_normal_, dtype=np.float64)
    p = np.asarray(tangent.plane_point_, dtype=np.float64)
    na, nb = n[a], n[b]
    if np.hypot(na, nb) < 1e-6 * np.linalg.norm(n):
        return None
    lo, hi = Y[:, [a, b]].min(axis=0), Y[:, [a, b]].max(axis=0)
    # line through (p_a, p_b) with direction (-nb, na)
    d = np.array([-nb, na]) / np.hypot(na, nb)
    span = 2.0 * float(np.hypot(*(hi - lo)))
    t = np.linspace(-span, span, 2)
    x, y = p[a] + t * d[0], p[b] + t * d[1]
    style = dict(color="k", linestyle=":", linewidth=1.2, label="zero-velocity plane")
    style.update(kw)
    line, = ax.plot(x, y, **style)
    pad = 0.05 * (hi - lo)
    ax.set_xlim(lo[0] - pad[0], hi[0] + pad[0])
    ax.set_ylim(lo[1] - pad[1], hi[1] + pad[1])
    line.set_gid("zero-velocity-plane")
    return line


def density(pts, *, bins: int | None = None, sigma: float = 1.5) -> np.ndarray:
    """Relative local density of 2-D or 3-D points in [0, 1] (rank of a smoothed histogram).

    O(N): a histogram on a regular grid (80 bins a side in 2-D, 40 in 3-D),
    Gaussian-smoothed, looked up per point and rank-normalised so the colour map
    spans the data.
    """
    from scipy.ndimage import gaussian_filter
    from scipy.stats import rankdata

    pts = np.asarray(pts, dtype=np.float64)
    if len(pts) < 2:
        return np.ones(len(pts))
    bins = bins or (80 if pts.shape[1] <= 2 else 40)
    H, edges = np.histogramdd(pts, bins=bins)
    H = gaussian_filter(H, sigma)
    idx = tuple(np.clip(np.searchsorted(e, pts[:, k], side="right") - 1, 0, bins - 1)
                for k, e in enumerate(edges))
    r = rankdata(H[idx], method="average")
    return (r - r.min()) / max(r.max() - r.min(), 1.0)


def arrow(ax, start, vec, *, color, label=None, lw=1.8, head=8.0, gid=None, fontsize=9):
    """An annotated arrow from ``start`` along ``vec`` (2-D data coordinates)."""
    start = np.asarray(start, dtype=float)
    end = start + np.asarray(vec, dtype=float)
    ann = ax.annotate("", xy=end, xytext=start,
                      arrowprops=dict(arrowstyle=f"-|>,head_length={head / 20:.2f},head_width={head / 40:.2f}",
                                      color=color, lw=lw, shrinkA=0, shrinkB=0))
    if gid:
        ann.set_gid(gid)
    if label:
        ax.annotate(label, xy=end, xytext=(3, 3), textcoords="offset points", color=color,
                    fontsize=fontsize, fontweight="bold")
    return ann


# ---------------------------------------------------------------- lip shapes
def front_view(points, dims: int, view=None) -> tuple[int, int, int | None]:
    """Axes (horizontal, vertical, depth) of a front view of lip points (V, 3).

    ``view`` may give them explicitly. 2-D data is drawn x–y. For 3-D data the
    horizontal axis is the one with the widest spread of the points (mouth width),
    the vertical the next (height) and depth the narrowest (protrusion).
    """
    if view is not None:
        h, v = int(view[0]), int(view[1])
        rest = [k for k in range(3) if k not in (h, v)]
        return h, v, (rest[0] if dims == 3 else None)
    if dims == 2:
        return 0, 1, None
    spread = np.ptp(np.asarray(points, dtype=np.float64), axis=0)
    order = np.argsort(-spread, kind="stable")
    return int(order[0]), int(order[1]), int(order[2])


def draw_shape(ax, points, *, dims, faces=None, values=None, norm=None, cmap=CMAP, color="#c86464",
               view=None, size=None, gid=None):
    """Draw one lip shape (V, 3) in front view on ``ax``.

    With ``faces`` the mesh is drawn as painter-sorted, Lambert-shaded triangles
    (viewer on the side of ``horizontal x vertical``); without, the points are a
    scatter. ``values`` (V,) colour it through ``cmap``/``norm``; otherwise ``color``.
    Returns the collection drawn.
    """
    P = np.asarray(points, dtype=np.float64)
    h, v, dep = front_view(P, dims, view)
    xy = P[:, [h, v]]
    cols = None
    if values is not None:
        norm = norm or Normalize(float(np.min(values)), float(np.max(values)) or 1.0)
        cols = cmap(norm(np.asarray(values, dtype=np.float64)))
    if faces is not None and len(faces) and dep is not None:
        F = np.asarray(faces)
        tri = P[F]                                         # (T, 3, 3)
        nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
        view_dir = np.cross(np.eye(3)[h], np.eye(3)[v])   # towards the viewer
        shade = 0.55 + 0.45 * np.abs(nrm @ view_dir)
        depth = tri.mean(axis=1) @ view_dir
        order = np.argsort(depth, kind="stable")          # far first
        base = cols[F].mean(axis=1) if cols is not None else np.tile(to_rgba(color), (len(F), 1))
        fc = base.copy()
        fc[:, :3] *= shade[:, None]
        pc = PolyCollection(tri[order][:, :, [h, v]], facecolors=fc[order], edgecolors="none",
                            linewidths=0, antialiased=False, rasterized=rasterize_for(len(F)))
        ax.add_collection(pc)
        ax.update_datalim(xy)
        ax.autoscale_view()
        coll = pc
    else:
        s = size if size is not None else marker_size(len(P), big=30.0, small=2.0)
        coll = ax.scatter(xy[:, 0], xy[:, 1], s=s, c=cols if cols is not None else color, linewidths=0,
                          rasterized=rasterize_for(len(P)))
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for sp in ax.spines.values():
        sp.set_visible(False)
    if gid:
        coll.set_gid(gid)
    return coll


def shape_points(manifold, frame_row) -> np.ndarray:
    """One frame row (C,) as points (V, 3), z = 0 for 2-D data."""
    from engine.corpus import frame_points

    return frame_points(np.asarray(frame_row), manifold.corpus_.dims).astype(np.float64)


def place_labels(ax, xy, labels, *, fontsize: float = 7.0, color="0.25", marker_pt: float = 7.0,
                 radii_pt=(4.0, 8.0, 13.0, 19.0)) -> int:
    """Write ``labels`` beside the data points ``xy`` without any two labels overlapping.

    Each label tries positions around its point (8 directions at growing distances,
    north-east first) and takes the first whose box overlaps no label placed before it,
    no other point's marker and stays inside the axes; failing that, the first that
    overlaps no label. A label with no free place is left out. Labels do not take part
    in the figure's layout, so the layout (and the checked places) stay as computed here.

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
    frame = ax.get_window_extent(renderer)
    angles = np.radians([45, 135, -45, -135, 0, 180, 90, -90])
    placed, left_out = [], 0
    for k, ((x, y), lab) in enumerate(zip(xy, labels)):
        best = None
        for strict in (True, False):
            for r in radii_pt:
                for a in angles:
                    dx, dy = r * np.cos(a), r * np.sin(a)
                    ha = "left" if dx > 0.5 else "right" if dx < -0.5 else "center"
                    va = "bottom" if dy > 0.5 else "top" if dy < -0.5 else "center"
                    t = ax.annotate(str(lab), xy=(x, y), xytext=(dx, dy), textcoords="offset points", ha=ha,
                                    va=va, fontsize=fontsize, color=color, annotation_clip=False)
                    t.set_in_layout(False)
                    bb = t.get_window_extent(renderer)
                    free = not any(bb.overlaps(o) for o in placed)
                    if strict:
                        free = (free and not any(bb.overlaps(m) for j, m in enumerate(markers) if j != k)
                                and frame.contains(bb.x0, bb.y0) and frame.contains(bb.x1, bb.y1))
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
    return left_out
