"""Figures of the shape space X and the variance of X and Y (paper figs 1a, 1b, 2c; scree)."""
from __future__ import annotations

import numpy as np
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from app.figures.style import (
    CMAP,
    draw_lips,
    fit_contour,
    font_pt,
    frame_sv,
    journal,
    legend_below,
    new_figure,
    one_column,
    require_fitted,
    scale_bar,
    shape_points,
    shape_view,
    shared_limits,
    talker_frame,
)

__all__ = ["make_fig1a", "make_fig1b", "make_fig2c", "make_scree"]

#: colours of fig 1b: X blue, Y red (the paper's)
X_COLOUR = "blue"
Y_COLOUR = "red"
#: the mean shape (no displacement) is drawn in neutral grey
MEAN_COLOUR = "0.72"
#: floor of the log axis of residual variance
RESIDUAL_FLOOR = 1e-6


@journal
def make_fig1a(manifold, *, components=(0, 1), n_sd: float = 2.0, view=None, width=None):
    """Fig. 1(a): principal components of X as lip shapes, coloured by displacement.

    One row per component: the mean shape moved −n_sd and +n_sd standard deviations
    along it, drawn in front view, each point (or triangle) coloured by its distance
    from the mean shape, blue (none) → red (largest, shared scale, in the corpus's unit);
    the mean shape itself between them in grey. Sparse markers are drawn on their lip
    contour; a scale bar gives the size.

    Parameters
    ----------
    manifold : engine.manifold.model.Manifold
        Fitted.
    components : sequence of int, default=(0, 1)
        Zero-based component indices (the paper shows the first two).
    n_sd : float, default=2.0
    view : (int, int) or None
        Axes (horizontal, vertical) of the talker's view coordinates
        (:func:`app.figures.style.shape_points`) to draw; None: the front view when the
        talker's frame is known (:func:`engine.recordings.orientation.anatomical_frame`), else the axes
        of the widest spread of the mean shape (:func:`app.figures.style.front_view`).
    width : float, optional
        Figure width in inches (default 180 mm, two journal columns; see :func:`app.figures.style.journal`).
    """
    require_fitted(manifold, "shape_")
    shape, corpus = manifold.shape_, manifold.corpus_
    comps = [int(c) for c in components if 0 <= int(c) < shape.n_components_]
    if not comps:
        raise ValueError(f"components {list(components)} out of range: the shape space has "
                         f"{shape.n_components_} components (0..{shape.n_components_ - 1})")
    frame = talker_frame(manifold)
    view = shape_view(manifold, view, frame)
    contour = fit_contour(manifold, frame)
    mean_pts = shape_points(manifold, shape.mean_, frame)
    offsets = (-n_sd, 0.0, n_sd)
    shapes = {(c, a): shape_points(manifold, shape.component_deformation(c, a) if a else shape.mean_, frame)
              for c in comps for a in offsets}
    disp = {k: np.linalg.norm(p - mean_pts, axis=1) for k, p in shapes.items()}
    vmax = max(float(d.max()) for d in disp.values()) or 1.0
    norm = Normalize(0.0, vmax)
    fig = new_figure(width, (0.30 if one_column(width) else 0.22) * width * len(comps) + 0.7)
    axs = fig.subplots(len(comps), 3, squeeze=False)
    for r, c in enumerate(comps):
        pct = 100 * float(shape.explained_variance_ratio_[c])
        for k, a in enumerate(offsets):
            ax = axs[r, k]
            draw_lips(ax, shapes[(c, a)], dims=corpus.dims, faces=corpus.faces, contour=contour,
                      values=disp[(c, a)] if a else None, norm=norm, color=MEAN_COLOUR, view=view,
                      gid=f"fig1a:pc{c + 1}:{a:+g}")
            ax.set_title("mean" if a == 0 else f"{a:+g} s.d.")
            if k == 0:
                ax.set_ylabel(f"PC{c + 1} ({pct:.1f}%)")
        # equal limits within a row so the deformation reads; a margin so no shape touches an edge
        shared_limits(axs[r], [shapes[(c, a)] for a in offsets], contour=contour, view=view, below=0.3)
        scale_bar(axs[r, 1], corpus.unit_label, gid=f"fig1a:scale:pc{c + 1}")
    sm = _mappable(norm)
    fig.colorbar(sm, ax=axs, shrink=0.8, label=f"displacement from the mean shape ({corpus.unit_label})")
    fig.suptitle(f"Principal components of X (mean ± {n_sd:g} s.d.)")
    fig.lipspace.update(components=comps, n_sd=n_sd, max_displacement=vmax)
    return fig


def _mappable(norm, cmap=CMAP):
    from matplotlib.cm import ScalarMappable

    sm = ScalarMappable(norm=norm, cmap=cmap)
    sm.set_array([])
    return sm


def residuals(ratio) -> np.ndarray:
    """Residual variance ``1 - cumsum(ratio)`` with the leading 0-component value 1.

    Clipped below at :data:`RESIDUAL_FLOOR` for the log axis; non-increasing.
    Returns ndarray of shape (len(ratio) + 1,).
    """
    ratio = np.clip(np.asarray(ratio, dtype=np.float64), 0.0, None)
    res = 1.0 - np.concatenate([[0.0], np.cumsum(ratio)])
    return np.maximum(np.minimum.accumulate(res), RESIDUAL_FLOOR)


@journal
def make_fig1b(manifold, *, max_components: int | None = 30, width=None, height: float | None = None):
    """Fig. 1(b): residual variance vs number of components, X blue, Y red (log y).

    X uses ``shape_.scree_`` (fraction of the total variance of F per computed
    component), Y ``embedding_.explained_variance_ratio_`` (fraction of the total
    variance of the centred distance matrix).

    Parameters
    ----------
    max_components : int or None, default=30
        Components shown (None: all computed).
    width, height : float, optional
        Inches (default width 180 mm; height 0.62 x width, 0.8 x on one column).
    """
    require_fitted(manifold, "shape_", "embedding_")
    rx = residuals(manifold.shape_.scree_)
    ry = residuals(manifold.embedding_.explained_variance_ratio_)
    if max_components is not None:
        rx, ry = rx[: max_components + 1], ry[: max_components + 1]
    fig = new_figure(width, height or (0.8 if one_column(width) else 0.5) * width)
    ax = fig.subplots()
    lx, = ax.semilogy(np.arange(len(rx)), rx, "-o", color=X_COLOUR, ms=2.5, label="X (shape PCA)")
    ly, = ax.semilogy(np.arange(len(ry)), ry, "-o", color=Y_COLOUR, ms=2.5, label="Y (speech task space)")
    lx.set_gid("fig1b:X")
    ly.set_gid("fig1b:Y")
    ax.set_xlabel("number of components")
    ax.set_ylabel("residual variance (fraction of the total)")
    ax.set_xlim(0, max(len(rx), len(ry)) - 1)
    ax.grid(True, which="both", alpha=0.3)
    legend_below(fig, [lx, ly], ncol=2)
    k3 = min(3, len(ry) - 1)
    ax.set_title(f"Residual variance: first {k3} dims of Y leave {100 * ry[k3]:.1f}%")
    fig.lipspace.update(residual_X=rx, residual_Y=ry)
    return fig


@journal
def make_fig2c(manifold, *, n_shapes: int = 7, quantiles=(0.03, 0.97), view=None, width=None):
    """Fig. 2(c): lip shapes indexed by increasing S, the opening (the lip aperture).

    Frames are ordered by their S coordinate (:func:`app.figures.style.frame_sv`). For each of
    ``n_shapes`` evenly spaced quantiles in ``quantiles`` the shape drawn is the mean
    F^x of the frames in that quantile bin, reconstructed to the lip points
    (``shape_.inverse_transform``): an honest average of real frames, no inverse map.
    Shapes are drawn from the front in the talker's frame; sparse markers on their lip
    contour, every panel with the same limits and a margin, a scale bar in the first.
    One row at two-column width; two rows on one column.
    """
    require_fitted(manifold, "shape_", "tangent_")
    if n_shapes < 2:
        raise ValueError(f"n_shapes must be >= 2, got {n_shapes}")
    corpus = manifold.corpus_
    frame = talker_frame(manifold)
    view = shape_view(manifold, view, frame)
    contour = fit_contour(manifold, frame)
    t = frame_sv(manifold)[:, 0]
    unit = manifold.tangent_.opening_unit_
    edges = np.quantile(t, np.linspace(quantiles[0], quantiles[1], n_shapes + 1))
    centres = 0.5 * (edges[:-1] + edges[1:])
    rows = 2 if one_column(width) and n_shapes > 4 else 1
    cols = int(np.ceil(n_shapes / rows))
    fig = new_figure(width, rows * 0.9 * width / cols + 0.75)
    grid = fig.subplots(rows, cols, squeeze=False)
    axs = list(grid.ravel()[:n_shapes])
    for ax in grid.ravel()[n_shapes:]:
        ax.set_axis_off()
    used, drawn = [], []
    for k, ax in enumerate(axs):
        sel = (t >= edges[k]) & (t <= edges[k + 1])
        if not sel.any():
            sel = np.abs(t - centres[k]) == np.abs(t - centres[k]).min()
        fx = np.asarray(manifold.Fx_, dtype=np.float64)[sel].mean(axis=0, keepdims=True)
        pts = shape_points(manifold, manifold.shape_.inverse_transform(fx)[0], frame)
        draw_lips(ax, pts, dims=corpus.dims, faces=corpus.faces, contour=contour, view=view, gid=f"fig2c:shape{k}")
        ax.set_title(f"S = {centres[k]:.1f} {unit}" if unit else f"S = {centres[k]:.3g}")
        used.append(int(sel.sum()))
        drawn.append(pts)
    shared_limits(axs, drawn, contour=contour, view=view, below=0.3)  # room under the shapes for the bar
    scale_bar(axs[0], corpus.unit_label, gid="fig2c:scale")
    fig.suptitle("Lip shapes indexed by increasing S (mean of the frames in each bin)")
    s_label = manifold.tangent_.sv_labels()[0]
    fig.supxlabel(f"{s_label}: each panel's bin centre", fontsize=font_pt())
    fig.lipspace.update(s_values=centres, frames_per_shape=used, shapes=drawn, view=view,
                        orientation=frame.describe())
    return fig


@journal
def make_scree(manifold, *, max_components: int | None = 30, width=None, height: float | None = None):
    """Scree of X and Y: explained-variance ratio per component with its cumulative sum.

    The number of shape components kept is a dashed line in the X panel, named in the
    shared legend below the panels (nothing is written over the bars). Side by side at
    two-column width, stacked on one column.
    """
    require_fitted(manifold, "shape_", "embedding_")
    sx = np.asarray(manifold.shape_.scree_, dtype=np.float64)
    sy = np.asarray(manifold.embedding_.explained_variance_ratio_, dtype=np.float64)
    if max_components is not None:
        sx, sy = sx[:max_components], sy[:max_components]
    narrow = one_column(width)
    fig = new_figure(width, height or (1.25 if narrow else 0.42) * width)
    axs = fig.subplots(2, 1) if narrow else fig.subplots(1, 2)
    m = int(manifold.shape_.n_components_)
    for ax, r, col, name in ((axs[0], sx, "blue", "X (shape PCA)"), (axs[1], sy, "red", "Y (speech task space)")):
        n = np.arange(1, len(r) + 1)
        bars = ax.bar(n, 100 * r, color=col, alpha=0.55)
        for patch in bars:
            patch.set_gid(f"scree:{name[0]}")
        ax.plot(n, 100 * np.cumsum(r), "-o", color=col, ms=2.5)
        ax.set_ylim(0, 100)
        ax.set_xlabel("component")
        ax.set_ylabel("% of variance")
        ax.set_title(name)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(True, axis="y", alpha=0.3)
    handles = [Patch(color="0.5", alpha=0.55, label="per component"),
               Line2D([], [], color="0.3", marker="o", ms=2.5, label="cumulative")]
    if m <= len(sx):
        kept = axs[0].axvline(m + 0.5, color="k", ls="--", lw=0.8, label=f"{m} shape components kept")
        kept.set_gid("scree:kept")
        handles.append(kept)
    legend_below(fig, handles)
    return fig
