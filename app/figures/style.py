"""Shared drawing helpers for the paper's figures (matplotlib, Agg, no pyplot).

Every figure is a :class:`matplotlib.figure.Figure` with its own
:class:`~matplotlib.backends.backend_agg.FigureCanvasAgg`, so nothing touches
pyplot's global state and no display is needed. Colours are the window's
(:mod:`app.figures.colours`); lip shapes are drawn by :mod:`app.figures.lipshapes`.

Figures are made for a journal page (:func:`journal`): the width is one column
(85 mm) or two (180 mm, the default) and every figure lays itself out for it, with
fonts of fixed point sizes (8 pt, 7 pt on one column; never below 6 pt, and no
mathtext, whose sub- and superscripts print smaller) so that they print at the size a
journal asks for without scaling; legends sit outside the plotting areas; manifold
coordinates are labelled "(arbitrary units)", lip shapes carry a scale bar in the
corpus's unit.
"""
from __future__ import annotations

import functools
import re

import numpy as np
from matplotlib import rc_context, rcParams
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

#: the screen resolution a view's pixels are taken to have (an "as on screen" export is the window's size at it)
SCREEN_DPI = 96.0
#: above this many points, large scatters are rasterised inside SVG/PDF
RASTERIZE_ABOVE = 1500

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


def fit_lines(fig, text, size: float, *, share: float = 0.9) -> str:
    """``text`` broken into lines ``share`` of the figure's width holds at ``size`` points, before the layout
    sees it (a line wider than the figure collapses the constrained layout)."""
    import textwrap

    chars = max(20, int(share * fig.get_figwidth() * 72.0 / (0.55 * size)))
    return "\n".join(textwrap.fill(line, chars) for line in str(text).split("\n"))


def below(ax, text, *, fontsize=None):
    """A note under an axes' x label, inside the constrained layout (never overlapping)."""
    size = font_pt(-1) if fontsize is None else fontsize
    text = fit_lines(ax.figure, text, size)
    # anchored under the x label itself (wherever the layout puts it), not at a fixed offset that a
    # tall tick label or x label can reach
    t = ax.annotate(text, xy=(0.5, 0.0), xycoords=ax.xaxis.label, xytext=(0, -3), textcoords="offset points",
                    va="top", ha="center", fontsize=size, color="0.25", annotation_clip=False)
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


def halo(width: float = 2.2):
    """A white outline behind text or lines drawn over data, so they stay legible on any colour."""
    from matplotlib import patheffects

    return [patheffects.withStroke(linewidth=width, foreground="white")]


def arrow(ax, start, vec, *, color, label=None, lw=1.8, head=8.0, gid=None, fontsize=None, zorder=6):
    """An arrow from ``start`` along ``vec`` (2-D data coordinates), drawn above the data; ``label`` is written
    just beyond its tip, in the arrow's direction, with a white halo."""
    start = np.asarray(start, dtype=float)
    vec = np.asarray(vec, dtype=float)
    end = start + vec
    ann = ax.annotate("", xy=end, xytext=start, zorder=zorder,
                      arrowprops=dict(arrowstyle=f"-|>,head_length={head / 20:.2f},head_width={head / 40:.2f}",
                                      color=color, lw=lw, shrinkA=0, shrinkB=0))
    if gid:
        ann.set_gid(gid)
    if label:
        d = ax.transData.transform(end) - ax.transData.transform(start)
        n = float(np.hypot(*d))
        u = d / n if n > 1e-9 else np.array([1.0, 0.0])
        t = ax.annotate(label, xy=end, xytext=(5 * u[0], 5 * u[1]), textcoords="offset points", color=color,
                        fontsize=font_pt() if fontsize is None else fontsize, fontweight="bold", zorder=zorder + 1,
                        ha="left" if u[0] > 0.3 else "right" if u[0] < -0.3 else "center",
                        va="bottom" if u[1] > 0.3 else "top" if u[1] < -0.3 else "center",
                        path_effects=halo(), annotation_clip=False)
        t.set_gid(f"{gid}:label" if gid else None)
    return ann


def reach_in_box(o, vec, lo, hi) -> float:
    """How far from ``o`` along ``vec`` the box [lo, hi] extends (inf if unbounded or ``o`` is outside it)."""
    o, vec = np.asarray(o, float), np.asarray(vec, float)
    if np.any(o < lo) or np.any(o > hi):
        return float("inf")
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(vec > 0, (hi - o) / vec, np.where(vec < 0, (lo - o) / vec, np.inf))
    return float(np.min(t))


def data_limits(ax, x, y, *, margin: float = 0.04):
    """Set ``ax``'s limits to the data's range (``x``, ``y``) with ``margin`` of it on each side: an axis spans
    what it shows, never an arrow's or a guide line's reach. The margin never carries an axis across zero:
    data that are all >= 0 (a lip aperture) start at 0 at the lowest, all <= 0 end at 0 at the highest, so no
    negative aperture is implied."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    for setter, v in ((ax.set_xlim, x), (ax.set_ylim, y)):
        v = v[np.isfinite(v)]
        lo, hi = (float(v.min()), float(v.max())) if v.size else (0.0, 1.0)
        pad = margin * (hi - lo) if hi > lo else max(abs(hi), 1.0) * 0.05
        a, b = lo - pad, hi + pad
        if lo >= 0 > a:
            a = 0.0
        if hi <= 0 < b:
            b = 0.0
        setter(a, b)


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
