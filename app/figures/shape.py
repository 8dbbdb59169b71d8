"""Figures of the shape space X and the variance of X and Y (paper figs 1a, 1b, 2c; scree).

Lip shapes are drawn as :class:`app.models.lip_drawing.LipDrawing` says (:mod:`app.figures.lipshapes`):
a measured surface as a surface, sensors as sensors joined by straight segments with the lip
aperture as a labelled segment.
"""
from __future__ import annotations

import numpy as np
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter, MaxNLocator, NullFormatter

from app.figures.colours import magnitude_cmap, palette_for
from app.figures.lipshapes import (
    clear_scale_bar,
    draw_frame,
    drawing_for,
    face_direction,
    key_cell,
    scale_bar,
    shape_points,
    shape_view,
    shared_limits,
    talker_frame,
)
from app.figures.style import (
    below,
    font_pt,
    frame_sv,
    journal,
    legend_below,
    new_figure,
    one_column,
    require_fitted,
)

__all__ = ["make_fig1a", "make_fig1b", "make_fig2c", "make_scree", "residuals", "NUMERICAL_FLOOR"]

#: the mean shape (no displacement, off the colour scale) has white markers
MEAN_COLOUR = "white"
#: residual variance at or below this fraction of the total is a numerical zero (the shape space is float32),
#: not data: fig 1b does not draw it
NUMERICAL_FLOOR = 1e-6


def space_colours(manifold, palette=None) -> dict:
    """The colours of X (the shape space) and Y (the speech task space) from the session's palette."""
    pal = palette_for(manifold, palette)
    return {"X": pal.colour("space", "X"), "Y": pal.colour("space", "Y")}


@journal
def make_fig1a(manifold, *, components=(0, 1), n_sd: float = 2.0, view=None, width=None, palette=None):
    """Fig. 1(a): principal components of X as lip shapes, coloured by displacement.

    One row per component: the mean shape moved -n_sd and +n_sd standard deviations
    along it, drawn from the front (in profile for 2-D midsagittal data), each sensor (or
    the surface) coloured by its distance from the mean shape (dark: none, light: the
    largest, one scale for the figure, in the corpus's unit); the mean shape between them
    in grey, its sensors labelled. Sensors are joined by straight segments and the lip
    aperture is a labelled segment (:mod:`app.figures.lipshapes`); a scale bar gives the size.

    Parameters
    ----------
    manifold : engine.manifold.model.Manifold
        Fitted.
    components : sequence of int, default=(0, 1)
        Zero-based component indices (the paper shows the first two).
    n_sd : float, default=2.0
    view : (int, int) or None
        Axes (horizontal, vertical) of the talker's view coordinates
        (:func:`app.figures.lipshapes.shape_points`) to draw; None: the front view when the
        talker's frame is known (:func:`engine.recordings.orientation.anatomical_frame`), else the axes
        of the widest spread of the mean shape.
    width : float, optional
        Figure width in inches (default 180 mm, two journal columns; see :func:`app.figures.style.journal`).
    palette : app.models.palette.SessionPalette, optional
        Unused (the figure has no categories); accepted like every figure's.
    """
    require_fitted(manifold, "shape_")
    shape, corpus = manifold.shape_, manifold.corpus_
    comps = [int(c) for c in components if 0 <= int(c) < shape.n_components_]
    if not comps:
        raise ValueError(f"components {list(components)} out of range: the shape space has "
                         f"{shape.n_components_} components (0..{shape.n_components_ - 1})")
    frame = talker_frame(manifold)
    view = shape_view(manifold, view, frame)
    drawing = drawing_for(manifold, frame)
    mean_pts = shape_points(manifold, shape.mean_, frame)
    offsets = (-n_sd, 0.0, n_sd)
    shapes = {(c, a): shape_points(manifold, shape.component_deformation(c, a) if a else shape.mean_, frame)
              for c in comps for a in offsets}
    disp = {k: np.linalg.norm(p - mean_pts, axis=1) for k, p in shapes.items()}
    vmax = max(float(d.max()) for d in disp.values()) or 1.0
    norm = Normalize(0.0, vmax)
    cmap = magnitude_cmap()
    fig = new_figure(width, (0.30 if one_column(width) else 0.22) * width * len(comps) + 0.7)
    axs = fig.subplots(len(comps), 3, squeeze=False)
    apertures, bars = {}, []
    for r, c in enumerate(comps):
        pct = 100 * float(shape.explained_variance_ratio_[c])
        for k, a in enumerate(offsets):
            ax = axs[r, k]
            out = draw_frame(ax, drawing, shapes[(c, a)], values=disp[(c, a)] if a else None, norm=norm, cmap=cmap,
                             color=MEAN_COLOUR, labels=(a == 0), view=view, gid=f"fig1a:pc{c + 1}:{a:+g}")
            apertures[(c, a)] = out["aperture_value"]
            ax.set_title("mean" if a == 0 else f"{a:+g} s.d.")
            if k == 0:
                ax.set_ylabel(f"PC{c + 1} ({pct:.1f}%)")
        # equal limits within a row so the deformation reads; a margin so no shape touches an edge
        shared_limits(axs[r], [shapes[(c, a)] for a in offsets], view=view, below=0.5 if drawing.has_aperture else 0.3)
        bars.append((axs[r], scale_bar(axs[r, 0], corpus.unit_label, gid=f"fig1a:scale:pc{c + 1}")))
        face_direction(axs[r, 0], drawing, gid=f"fig1a:front:pc{c + 1}")
    fig.colorbar(_mappable(norm, cmap), ax=axs, shrink=0.8,
                 label=f"displacement from the mean shape ({corpus.unit_label})")
    fig.suptitle(f"Principal components of X (mean \u00b1 {n_sd:g} s.d.)")
    for row, bar in bars:  # against the final layout: nothing in its panel meets the scale bar
        clear_scale_bar(fig, row, bar)
    fig.lipspace.update(components=comps, n_sd=n_sd, max_displacement=vmax, drawing=drawing.kind,
                        apertures=apertures)
    return fig


def _mappable(norm, cmap):
    from matplotlib.cm import ScalarMappable

    sm = ScalarMappable(norm=norm, cmap=cmap)
    sm.set_array([])
    return sm


def residuals(ratio) -> np.ndarray:
    """Residual variance ``1 - cumsum(ratio)`` with the leading 0-component value 1, non-increasing.

    Values at or below :data:`NUMERICAL_FLOOR` (a numerical zero) are NaN: not data, never drawn.
    Returns ndarray of shape (len(ratio) + 1,).
    """
    ratio = np.clip(np.asarray(ratio, dtype=np.float64), 0.0, None)
    res = np.minimum.accumulate(1.0 - np.concatenate([[0.0], np.cumsum(ratio)]))
    return np.where(res > NUMERICAL_FLOOR, res, np.nan)


@journal
def make_fig1b(manifold, *, max_components: int | None = 30, width=None, height: float | None = None,
               palette=None):
    """Fig. 1(b): residual variance vs number of components, X and Y (log y).

    X uses ``shape_.scree_`` (fraction of the total variance of F per computed
    component), Y ``embedding_.explained_variance_ratio_`` (fraction of the total
    variance of the centred distance matrix). A curve stops where what is left is a
    numerical zero (at most :data:`NUMERICAL_FLOOR` of the total), which a note says; the
    colours of X and Y are the session palette's (kind ``"space"``).

    Parameters
    ----------
    max_components : int or None, default=30
        Components shown (None: all computed).
    width, height : float, optional
        Inches (default width 180 mm; height 0.62 x width, 0.8 x on one column).
    palette : app.models.palette.SessionPalette, optional
        The session's palette (default: the corpus's own).
    """
    require_fitted(manifold, "shape_", "embedding_")
    rx = residuals(manifold.shape_.scree_)
    ry = residuals(manifold.embedding_.explained_variance_ratio_)
    if max_components is not None:
        rx, ry = rx[: max_components + 1], ry[: max_components + 1]
    col = space_colours(manifold, palette)
    fig = new_figure(width, height or (0.8 if one_column(width) else 0.5) * width)
    ax = fig.subplots()
    # in per cent of the total, ticks as plain numbers (a mathtext power's exponent prints below 6 pt)
    lx, = ax.semilogy(np.arange(len(rx)), 100 * rx, "-o", color=col["X"], ms=2.5, label="X (shape PCA)")
    ly, = ax.semilogy(np.arange(len(ry)), 100 * ry, "-s", color=col["Y"], ms=2.5, label="Y (speech task space)")
    lx.set_gid("fig1b:X")
    ly.set_gid("fig1b:Y")
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
    ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("number of components")
    ax.set_ylabel("residual variance (% of the total)")
    n = max(len(rx), len(ry))
    ax.set_xlim(-0.3, n - 0.7)
    shown = 100 * np.concatenate([rx[np.isfinite(rx)], ry[np.isfinite(ry)]])
    lo, hi = float(shown.min()), float(shown.max())
    ax.set_ylim(lo / 10 ** (0.04 * np.log10(hi / lo) + 0.05), hi * 10 ** (0.04 * np.log10(hi / lo) + 0.05))
    ax.grid(True, which="major", alpha=0.3)
    legend_below(fig, [lx, ly], ncol=2)
    k3 = min(3, len(ry) - 1)
    left = ry[k3] if np.isfinite(ry[k3]) else 0.0
    ax.set_title(f"Residual variance: the first {k3} dims of Y leave {100 * left:.1f}%")
    zero = [(name, int(np.flatnonzero(~np.isfinite(r))[0])) for name, r in (("X", rx), ("Y", ry))
            if (~np.isfinite(r)).any()]
    if zero:
        below(ax, "; ".join(f"{name}: numerical zero (\u2264 {NUMERICAL_FLOOR:g}) from {k} components on, not drawn"
                            for name, k in zero))
    fig.lipspace.update(residual_X=rx, residual_Y=ry, numerical_zero=dict(zero))
    return fig


@journal
def make_fig2c(manifold, *, n_shapes: int = 7, quantiles=(0.03, 0.97), view=None, width=None, palette=None):
    """Fig. 2(c): lip shapes indexed by increasing S, the opening (the lip aperture).

    Frames are ordered by their S coordinate (:func:`app.figures.style.frame_sv`). For each of
    ``n_shapes`` evenly spaced quantiles in ``quantiles`` the shape drawn is the mean
    F^x of the frames in that quantile bin, reconstructed to the lip points
    (``shape_.inverse_transform``): an honest average of real frames, no inverse map.
    Shapes are drawn from the front (in profile for 2-D midsagittal data) in the talker's
    frame, sensors as sensors with the lip aperture as a labelled segment
    (:mod:`app.figures.lipshapes`); every panel has the same limits and a margin, the first the
    sensors' labels. The scale bar (and a profile's face direction) take a cell of their own after the
    shapes, at the shapes' scale: they never meet a shape. Four columns at two-column width, three on one.
    """
    require_fitted(manifold, "shape_", "tangent_")
    if n_shapes < 2:
        raise ValueError(f"n_shapes must be >= 2, got {n_shapes}")
    corpus = manifold.corpus_
    frame = talker_frame(manifold)
    view = shape_view(manifold, view, frame)
    drawing = drawing_for(manifold, frame)
    t = frame_sv(manifold)[:, 0]
    unit = manifold.tangent_.opening_unit_
    edges = np.quantile(t, np.linspace(quantiles[0], quantiles[1], n_shapes + 1))
    centres = 0.5 * (edges[:-1] + edges[1:])
    cols = min(3 if one_column(width) else 4, n_shapes + 1)
    rows = int(np.ceil((n_shapes + 1) / cols))  # one cell more: the scale bar's
    fig = new_figure(width, rows * 0.8 * width / cols + 0.8)
    grid = fig.subplots(rows, cols, squeeze=False)
    axs = list(grid.ravel()[:n_shapes])
    key = grid.ravel()[n_shapes]
    for ax in grid.ravel()[n_shapes + 1:]:
        ax.set_axis_off()
    used, drawn, apertures = [], [], []
    Fx = np.asarray(manifold.Fx_, dtype=np.float64)
    for k, ax in enumerate(axs):
        sel = (t >= edges[k]) & (t <= edges[k + 1])
        if not sel.any():
            sel = np.abs(t - centres[k]) == np.abs(t - centres[k]).min()
        fx = Fx[sel].mean(axis=0, keepdims=True)
        pts = shape_points(manifold, manifold.shape_.inverse_transform(fx)[0], frame)
        out = draw_frame(ax, drawing, pts, labels=(k == 0), view=view, gid=f"fig2c:shape{k}")
        ax.set_title(f"S = {centres[k]:.1f} {unit}" if unit else f"S = {centres[k]:.3g}")
        used.append(int(sel.sum()))
        drawn.append(pts)
        apertures.append(out["aperture_value"])
    # room under the shapes for the aperture's value; the key cell at the same scale as the shapes
    shared_limits([*axs, key], drawn, view=view, below=0.25 if drawing.has_aperture else 0.0)
    key_cell(key, corpus.unit_label, drawing, gid="fig2c")
    fig.suptitle("Lip shapes indexed by increasing S (mean of the frames in each bin)")
    s_label = manifold.tangent_.sv_labels()[0]
    what = f"{s_label}: each panel's bin centre"
    if drawing.has_aperture:
        what += "; dashed: the shape's lip aperture"
    fig.supxlabel(what, fontsize=font_pt())
    fig.lipspace.update(s_values=centres, frames_per_shape=used, shapes=drawn, view=view,
                        orientation=frame.describe(), drawing=drawing.kind, apertures=apertures)
    return fig


@journal
def make_scree(manifold, *, max_components: int | None = 30, width=None, height: float | None = None,
               palette=None):
    """Scree of X and Y: explained-variance ratio per component with its cumulative sum.

    The number of shape components kept is a dashed line in the X panel, named in the
    shared legend below the panels (nothing is written over the bars). Side by side at
    two-column width, stacked on one column. X and Y take the session palette's colours
    (kind ``"space"``), as in fig. 1b.
    """
    require_fitted(manifold, "shape_", "embedding_")
    sx = np.asarray(manifold.shape_.scree_, dtype=np.float64)
    sy = np.asarray(manifold.embedding_.explained_variance_ratio_, dtype=np.float64)
    if max_components is not None:
        sx, sy = sx[:max_components], sy[:max_components]
    col = space_colours(manifold, palette)
    narrow = one_column(width)
    fig = new_figure(width, height or (1.25 if narrow else 0.42) * width)
    axs = fig.subplots(2, 1) if narrow else fig.subplots(1, 2)
    m = int(manifold.shape_.n_components_)
    for ax, r, c, name in ((axs[0], sx, col["X"], "X (shape PCA)"), (axs[1], sy, col["Y"], "Y (speech task space)")):
        n = np.arange(1, len(r) + 1)
        bars = ax.bar(n, 100 * r, color=c, alpha=0.6)
        for patch in bars:
            patch.set_gid(f"scree:{name[0]}")
        ax.plot(n, 100 * np.cumsum(r), "-o", color=c, ms=2.5)
        ax.set_ylim(0, 100)
        ax.set_xlim(0.4, len(r) + 0.6)
        ax.set_xlabel("component")
        ax.set_ylabel("% of variance")
        ax.set_title(name)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(True, axis="y", alpha=0.3)
    handles = [Patch(color="0.5", alpha=0.6, label="per component"),
               Line2D([], [], color="0.3", marker="o", ms=2.5, label="cumulative")]
    if m <= len(sx):
        kept = axs[0].axvline(m + 0.5, color="k", ls="--", lw=0.8, label=f"{m} shape components kept")
        kept.set_gid("scree:kept")
        handles.append(kept)
    legend_below(fig, handles)
    return fig
