"""Shared drawing helpers for the paper's figures (matplotlib, Agg, no pyplot).

Every figure is a :class:`matplotlib.figure.Figure` with its own
:class:`~matplotlib.backends.backend_agg.FigureCanvasAgg`, so nothing touches
pyplot's global state and no display is needed. Colours follow the paper:
blue = low / far / sparse, red = high / near / dense (matplotlib's ``jet``).

Figures are made for a journal page (:func:`journal`): the width is one column
(85 mm) or two (180 mm, the default) and every figure lays itself out for it, with
fonts of fixed point sizes (8 pt, 7 pt on one column; never below 6 pt) so that
they print at the size a journal asks for without scaling; legends sit outside the
plotting areas; manifold coordinates are labelled "(arbitrary units)", lip shapes
carry a scale bar in the corpus's unit.
"""
from __future__ import annotations

import functools
import re

import numpy as np
from matplotlib import colormaps, rc_context, rcParams
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
#: the four tangent classes (``engine.manifold.tangent.TangentFrames.classes_`` 0..3)
CLASS_COLOURS = ("#d62728", "#ff9896", "#1f4fb4", "#8fb8ff")

#: above this many points, large scatters are rasterised inside SVG/PDF
RASTERIZE_ABOVE = 4000

#: journal column widths in mm: one column and two columns (the default)
COLUMN_WIDTHS_MM = {"85mm": 85.0, "180mm": 180.0}
DEFAULT_WIDTH_MM = 180.0
#: narrowest and widest figure (mm) :func:`parse_width` accepts
WIDTH_RANGE_MM = (40.0, 260.0)
#: at or below this width (mm) a figure takes its one-column layout (panels stacked) and 7-pt fonts
ONE_COLUMN_MM = 120.0
#: smallest font size (pt) any text is drawn at
MIN_FONT_PT = 6.0
#: unit label of manifold coordinates (F^y, S, V): they have none
ARBITRARY = "(arbitrary units)"
_UNIT_MM = {"mm": 1.0, "cm": 10.0, "in": 25.4, "": 1.0}


def parse_width(text) -> float:
    """A figure width as typed (``"85mm"``, ``"180mm"``, ``"8.5cm"``, ``"3.35in"``; a bare number is mm) in inches.

    Raises ValueError naming the accepted range and the journal widths.
    """
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*(mm|cm|in)?\s*", str(text))
    if m is None:
        raise ValueError(f"width {text!r}: expected a length such as 85mm (one journal column) or 180mm (two)")
    mm = float(m.group(1)) * _UNIT_MM[m.group(2) or ""]
    lo, hi = WIDTH_RANGE_MM
    if not lo <= mm <= hi:
        raise ValueError(f"width {text!r} is {mm:g} mm; expected {lo:g} to {hi:g} mm (85mm: one journal column, "
                         "180mm: two)")
    return mm / 25.4


def one_column(width_in: float) -> bool:
    """Whether a figure of this width (inches) takes its narrow, one-column layout."""
    return width_in * 25.4 <= ONE_COLUMN_MM


def journal_rc(width_in: float) -> dict:
    """matplotlib settings of a figure ``width_in`` inches wide: fixed point sizes and thin lines.

    Fonts: 8 pt (7 pt on one column), tick labels and legends 1 pt smaller, never below
    :data:`MIN_FONT_PT`. (How text goes into PDF and SVG files is set where they are written:
    :data:`app.figures.export.EMBEDDED_FONTS`.)
    """
    base = 7.0 if one_column(width_in) else 8.0
    small = max(MIN_FONT_PT, base - 1.0)
    return {"font.size": base, "axes.titlesize": base, "axes.labelsize": base, "figure.titlesize": base + 1.0,
            "xtick.labelsize": small, "ytick.labelsize": small, "legend.fontsize": small,
            "axes.linewidth": 0.6, "xtick.major.width": 0.6, "ytick.major.width": 0.6, "xtick.major.size": 2.5,
            "ytick.major.size": 2.5, "lines.linewidth": 1.0, "lines.markersize": 3.0, "legend.handlelength": 1.6}


def font_pt(delta: float = 0.0) -> float:
    """The current base font size plus ``delta`` points, at least :data:`MIN_FONT_PT` (inside :func:`journal`)."""
    return max(MIN_FONT_PT, float(rcParams["font.size"]) + delta)


def journal(fn):
    """Decorator of a figure function ``fn(manifold, ..., width=None)``: ``width`` (inches; default
    :data:`DEFAULT_WIDTH_MM`) is passed on and the figure is built in :func:`journal_rc` for it."""

    @functools.wraps(fn)
    def wrapper(manifold, *args, width=None, **kw):
        w = DEFAULT_WIDTH_MM / 25.4 if width is None else float(width)
        if not WIDTH_RANGE_MM[0] / 25.4 - 1e-9 <= w <= WIDTH_RANGE_MM[1] / 25.4 + 1e-9:
            raise ValueError(f"width {w:.3g} in is outside {WIDTH_RANGE_MM[0]:g}-{WIDTH_RANGE_MM[1]:g} mm "
                             "(85 mm: one journal column, 180 mm: two)")
        with rc_context(journal_rc(w)):
            fig = fn(manifold, *args, width=w, **kw)
            wrap_long_texts(fig)
        fig.lipspace.setdefault("width_mm", w * 25.4)
        return fig

    return wrapper


def wrap_long_texts(fig, *, passes: int = 3) -> int:
    """Break every text too long for the figure (a title naming a long sentence, an axis label on a narrow
    panel) into lines that fit, so that no text is clipped at the figure's edge; returns how many were wrapped.

    A text counts as too long when, along its direction, it is longer than 96% of the figure, or it is laid
    out by the figure (titles, axis and colour-bar labels) and sticks out of it.
    """
    import textwrap

    from matplotlib.text import Text

    wrapped = 0
    for _ in range(passes):
        fig.draw_without_rendering()
        renderer = fig.canvas.get_renderer()
        page = fig.bbox
        changed = False
        for t in fig.findobj(lambda a: isinstance(a, Text) and a.get_visible() and bool(a.get_text().strip())):
            bb = t.get_window_extent(renderer)
            vertical = abs((t.get_rotation() % 180) - 90) < 1
            length, room = (bb.height, page.height) if vertical else (bb.width, page.width)
            out = bb.x0 < page.x0 - 0.5 or bb.x1 > page.x1 + 0.5 or bb.y0 < page.y0 - 0.5 or bb.y1 > page.y1 + 0.5
            if not (length > 0.96 * room or (out and t.get_in_layout())):
                continue
            text = t.get_text()
            if "$" in text:  # never break mathtext
                continue
            lines = text.split("\n")
            longest = max(len(x) for x in lines)
            chars = max(8, int(longest * min(0.9 * room / max(length, 1.0), 0.85)))
            new = "\n".join(textwrap.fill(x, chars) for x in lines)
            if new != text:
                t.set_text(new)
                wrapped += 1
                changed = True
        if not changed:
            break
    return wrapped


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
        raise ValueError(f"figures need a fitted engine.manifold.model.Manifold (missing {', '.join(missing)}); "
                         "fit one with Manifold().fit(corpus) or load one with Manifold.load(path)")


def below(ax, text, *, fontsize=None):
    """A note under an axes' x label, inside the constrained layout (never overlapping)."""
    # anchored under the x label itself (wherever the layout puts it), not at a fixed offset that a
    # tall tick label or x label can reach
    t = ax.annotate(text, xy=(0.5, 0.0), xycoords=ax.xaxis.label, xytext=(0, -3), textcoords="offset points",
                    va="top", ha="center", fontsize=font_pt(-1) if fontsize is None else fontsize, color="0.25",
                    annotation_clip=False)
    t.set_gid("note")
    return t


def rasterize_for(n: int) -> bool:
    return n > RASTERIZE_ABOVE


def marker_size(n: int, *, big: float = 12.0, small: float = 1.0) -> float:
    """Scatter marker area (pt^2) that keeps ``n`` points readable on a small panel (smaller inside
    :func:`journal`, whose 6-8 pt fonts make the page's scale)."""
    scale = float(rcParams["font.size"]) / 10.0
    return float(np.clip(4000.0 / max(n, 1), small, big)) * scale


# ---------------------------------------------------------------- Y coordinates
def y3(manifold) -> np.ndarray:
    """First three dims of F^y as float64, (N, 3) (padded with zeros if Y has fewer)."""
    Fy = np.asarray(manifold.Fy_, dtype=np.float64)
    if Fy.shape[1] >= 3:
        return Fy[:, :3]
    return np.hstack([Fy, np.zeros((Fy.shape[0], 3 - Fy.shape[1]))])


def sv_basis(tangent) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(origin (3,), S (3,), V (3,)): the global shape and velocity directions
    (:meth:`engine.manifold.tangent.TangentFrames.sv_basis`)."""
    return tangent.sv_basis()


def frame_sv(manifold) -> np.ndarray:
    """Per frame (S, V), (N, 2): the opening and its velocity read on the manifold
    (:meth:`engine.manifold.tangent.TangentFrames.sv_coordinates`, which the frame table uses too).
    Opening frames lie at V > 0; speech cycles are the paper's loops in this plane."""
    return manifold.tangent_.sv_coordinates()


def state_sv(manifold) -> np.ndarray:
    """Per state (S, V), (K, 2): the mean of its frames' :func:`frame_sv`."""
    st = manifold.states_
    K = st.centroids_.shape[0]
    labels = np.asarray(st.labels_)
    P = frame_sv(manifold)
    cnt = np.maximum(np.bincount(labels, minlength=K), 1).astype(np.float64)
    return np.column_stack([np.bincount(labels, weights=P[:, j], minlength=K) / cnt for j in range(2)])


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


def arrow(ax, start, vec, *, color, label=None, lw=1.8, head=8.0, gid=None, fontsize=None):
    """An annotated arrow from ``start`` along ``vec`` (2-D data coordinates)."""
    start = np.asarray(start, dtype=float)
    end = start + np.asarray(vec, dtype=float)
    ann = ax.annotate("", xy=end, xytext=start,
                      arrowprops=dict(arrowstyle=f"-|>,head_length={head / 20:.2f},head_width={head / 40:.2f}",
                                      color=color, lw=lw, shrinkA=0, shrinkB=0))
    if gid:
        ann.set_gid(gid)
    if label:
        t = ax.annotate(label, xy=end, xytext=(3, 3), textcoords="offset points", color=color,
                        fontsize=font_pt() if fontsize is None else fontsize, fontweight="bold")
        t.set_gid(f"{gid}:label" if gid else None)
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
    cols = _colours(values, norm, cmap)
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
    return _shape_panel(ax, coll, gid)


def _colours(values, norm, cmap):
    """RGBA (V, 4) of ``values`` through ``cmap`` / ``norm`` (their own range without one), or None."""
    if values is None:
        return None
    norm = norm or Normalize(float(np.min(values)), float(np.max(values)) or 1.0)
    return cmap(norm(np.asarray(values, dtype=np.float64)))


def _shape_panel(ax, coll, gid):
    """A lip-shape panel: equal aspect, no ticks or spines (a scale bar gives the size); ``coll`` gets ``gid``."""
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for sp in ax.spines.values():
        sp.set_visible(False)
    if gid:
        coll.set_gid(gid)
    return coll


def talker_frame(manifold):
    """The talker's frame of the manifold's corpus (:func:`engine.recordings.orientation.anatomical_frame`)."""
    from engine.recordings.orientation import anatomical_frame

    return anatomical_frame(manifold.corpus_, manifold.shape_.mean_)


def shape_points(manifold, frame_row, frame=None) -> np.ndarray:
    """One frame row (C,) as points (V, 3) in the talker's view coordinates (x the talker's left, y up, z
    towards the viewer; 2-D: x forward, y up, z = 0), ``frame`` as :func:`talker_frame` gives it."""
    from engine.recordings.corpus import frame_points

    frame = talker_frame(manifold) if frame is None else frame
    row = frame.view_frames(np.asarray(frame_row, np.float64)[None])[0]
    return frame_points(row, manifold.corpus_.dims).astype(np.float64)


def shape_view(manifold, view, frame=None):
    """``view`` if given; else (0, 1), the front view of :func:`shape_points`, when the talker's frame is
    known, and None (the widest spread) when it is not."""
    if view is not None:
        return view
    frame = talker_frame(manifold) if frame is None else frame
    return (0, 1) if frame.source != "none" else None


def place_labels(ax, xy, labels, *, fontsize: float = 7.0, color="0.25", marker_pt: float = 7.0,
                 radii_pt=(4.0, 8.0, 13.0, 19.0), placed_texts=None) -> int:
    """Write ``labels`` beside the data points ``xy`` without any two labels overlapping.

    Each label tries positions around its point (8 directions at growing distances,
    north-east first) and takes the first whose box overlaps no label placed before it,
    no other point's marker and stays inside the axes; failing that, the first that
    overlaps no label and stays inside the figure. A label with no free place is left out.
    Labels do not take part in the figure's layout, so the layout (and the checked places)
    stay as computed here. ``placed_texts``: a list that receives the annotations drawn.

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
    page = fig.bbox
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
                    free = (not any(bb.overlaps(o) for o in placed) and page.contains(bb.x0, bb.y0)
                            and page.contains(bb.x1, bb.y1))
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
        if placed_texts is not None:
            placed_texts.append(best[0])
    return left_out


# ---------------------------------------------------------------- journal layout helpers
def legend_below(fig, handles, *, ncol=None, gid=None):
    """One legend for the figure, below every panel (outside all plotting areas: it never covers data)."""
    handles = [h for h in handles if h is not None]
    ncol = ncol or min(len(handles), 2 if one_column(fig.get_figwidth()) else 4)
    leg = fig.legend(handles=handles, loc="outside lower center", ncol=max(1, ncol), frameon=False)
    if gid:
        leg.set_gid(gid)
    return leg


def nice_length(span: float) -> float:
    """A round length (1, 2 or 5 x 10^k) of about a quarter of ``span`` for a scale bar."""
    span = float(span)
    if not span > 0:
        return 1.0
    target = 0.25 * span
    k = np.floor(np.log10(target))
    for m in (5.0, 2.0, 1.0):
        if m * 10 ** k <= target:
            return float(m * 10 ** k)
    return float(10 ** k)


def scale_bar(ax, unit: str, *, length=None, gid=None):
    """A horizontal scale bar in the lower left of a lip-shape panel, labelled with its length and ``unit``.

    Call after the panel's limits are final. Returns the bar's Line2D.
    """
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    L = nice_length(x1 - x0) if length is None else float(length)
    bx, by = x0 + 0.06 * (x1 - x0), y0 + 0.06 * (y1 - y0)
    line, = ax.plot([bx, bx + L], [by, by], color="0.15", lw=1.2, solid_capstyle="butt")
    t = ax.annotate(f"{L:g} {unit}", xy=(bx + L / 2, by), xytext=(0, 1.5), textcoords="offset points", ha="center",
                    va="bottom", fontsize=font_pt(-1), color="0.15")
    if gid:
        line.set_gid(gid)
        t.set_gid(f"{gid}:label")
    return line


def fit_contour(manifold, frame=None):
    """A :class:`engine.recordings.lipcontour.LipContour` fitted on the mean shape in view coordinates, for sparse lip
    markers with roles (3-D, no faces); None otherwise (meshes are drawn as meshes)."""
    c = manifold.corpus_
    if c.faces is not None or c.point_roles is None or c.dims != 3:
        return None
    from engine.recordings.lipcontour import LipContour

    try:
        return LipContour(n_samples=64).fit(shape_points(manifold, manifold.shape_.mean_, frame), c.point_roles)
    except ValueError:
        return None


def draw_lips(ax, points, *, dims, faces=None, contour=None, values=None, norm=None, cmap=CMAP, color="#c86464",
              view=None, gid=None):
    """One lip shape (V, 3, view coordinates) on ``ax``: a mesh, sparse markers on their lip contour (a closed
    outline through them, lightly filled, the sensors as dots on it), or bare points.

    Returns the collection of the drawn points (sensors) or triangles, with ``gid``.
    """
    if contour is None or faces is not None:
        return draw_shape(ax, points, dims=dims, faces=faces, values=values, norm=norm, cmap=cmap, color=color,
                          view=view, gid=gid)
    h, v = (0, 1) if view is None else (int(view[0]), int(view[1]))
    C = contour.contour(np.asarray(points, np.float64))
    loop = np.vstack([C[:, [h, v]], C[:1, [h, v]]])
    ax.fill(loop[:, 0], loop[:, 1], color=color, alpha=0.22, lw=0, zorder=1)
    outline, = ax.plot(loop[:, 0], loop[:, 1], color=color, lw=1.4, zorder=2)
    if gid:
        outline.set_gid(f"{gid}:contour")
    P = np.asarray(points, np.float64)
    cols = _colours(values, norm, cmap)
    coll = ax.scatter(P[:, h], P[:, v], s=14, c=cols if cols is not None else color, edgecolors="0.2",
                      linewidths=0.4, zorder=3)
    ax.update_datalim(loop)
    return _shape_panel(ax, coll, gid)


def shared_limits(axs, shapes, *, contour=None, view=None, margin=0.15, below=0.0):
    """Equal limits on every panel of ``axs`` holding all ``shapes`` (list of (V, 3) view points; their contours
    too) with ``margin`` of the larger extent on every side, so no shape touches a panel's edge, and ``below``
    of it more at the bottom (room for a :func:`scale_bar`)."""
    h, v = (0, 1) if view is None else (int(view[0]), int(view[1]))
    pts = [np.asarray(P, np.float64)[:, [h, v]] for P in shapes]
    if contour is not None:
        pts += [contour.contour(np.asarray(P, np.float64))[:, [h, v]] for P in shapes]
    allp = np.concatenate(pts)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    span = float(max(np.ptp(allp, axis=0).max(), 1e-9))
    pad = margin * span
    for ax in axs:
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad - below * span, hi[1] + pad)
