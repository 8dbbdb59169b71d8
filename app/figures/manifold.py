"""Paper fig. 2(a): the manifold in the first three dimensions of Y, with S, V and an example trajectory."""
from __future__ import annotations

import numpy as np
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from app.figures.colours import ORIGINAL, S_COLOUR, V_COLOUR, density_cmap
from app.figures.style import (
    ARBITRARY,
    arrow,
    data_limits,
    density,
    font_pt,
    halo,
    journal,
    legend_below,
    marker_size,
    new_figure,
    one_column,
    plane_trace,
    rasterize_for,
    reach_in_box,
    require_fitted,
    sv_basis,
    y3,
)

__all__ = ["make_fig2a", "example_segment", "PANELS"]

PANELS = ((0, 1), (0, 2), (1, 2))
#: direction marks along the example trajectory
N_DIRECTION_MARKS = 4


def example_segment(manifold, utterance=None, *, n_frames: int = 45) -> np.ndarray:
    """Frame indices of an example stretch of speech: ``n_frames`` from an utterance.

    ``utterance`` is an id or index; None takes the utterance of median length. The
    stretch starts a quarter of the way into the spare frames (past leading silence).
    """
    corpus = manifold.corpus_
    u = _utterance(corpus, utterance)
    start = u.start + (u.n_frames - min(n_frames, u.n_frames)) // 4
    return np.arange(start, min(u.stop, start + n_frames))


def _utterance(corpus, utterance):
    if utterance is None:
        lengths = np.array([u.n_frames for u in corpus.utterances])
        return corpus.utterances[int(np.argsort(lengths, kind="stable")[len(lengths) // 2])]
    if isinstance(utterance, (int, np.integer)):
        n = len(corpus.utterances)
        if not -n <= int(utterance) < n:
            raise ValueError(f"utterance index {utterance} out of range: the corpus has {n} utterances")
        return corpus.utterances[int(utterance)]
    try:
        return corpus.utterance(str(utterance))
    except KeyError as exc:
        raise ValueError(exc.args[0]) from None


@journal
def make_fig2a(manifold, *, utterance=None, n_local: int = 4, n_traj: int = 45, view3d=(22, -60), width=None,
               palette=None):
    """Fig. 2(a): the manifold in the first three dims of Y.

    Three 2-D projections (Y1-Y2, Y1-Y3, Y2-Y3; the paper's caption speaks of density
    "in each projection", and flat panels export cleanly to SVG/PDF) and a 3-D view
    (mplot3d, ``view3d`` = (elevation, azimuth) in degrees). Points are coloured by their
    density in that projection (in 3-D for the 3-D view) with the window's density map
    (:func:`app.figures.colours.density_cmap`), densest drawn last. Drawn above the points:
    the global S and V from the plane point (thick, labelled in every panel), local s_i and
    v_i at ``n_local`` frames spread along S (thin), the zero-velocity plane's trace
    (dotted; a translucent patch in 3-D) and an example trajectory (``n_traj`` frames of
    ``utterance``, black, with arrowheads giving its direction). Each panel spans the data.
    The panels' sizes follow the data's extents and the figure's height follows them, so
    the equal-aspect panels fill their cells; the density colour bar and the legend lie
    below them. On one journal column (:func:`app.figures.style.one_column`) the legend takes
    the 3-D view's cell: a 3-D view an inch wide shows nothing the projections do not.
    ``palette`` is accepted like every figure's (the figure has no categories).
    """
    require_fitted(manifold, "tangent_")
    tan = manifold.tangent_
    Y = y3(manifold)
    N = len(Y)
    o, S, V = sv_basis(tan)
    extent = float(np.ptp(Y, axis=0).max()) or 1.0
    t = (Y - o) @ S
    # local frames: in each of n_local S-bins the frame in the densest spot
    dens3 = density(Y)
    edges = np.quantile(t, np.linspace(0.15, 0.85, n_local + 1))
    local = []
    for k in range(n_local):
        idx = np.flatnonzero((t >= edges[k]) & (t <= edges[k + 1]))
        if len(idx):
            local.append(int(idx[np.argmax(dens3[idx])]))
    traj = example_segment(manifold, utterance, n_frames=n_traj)
    # a corner layout sized by the data's extents, so that equal-aspect panels fill their cells (no empty
    # cell): Y1-Y2 above Y1-Y3 (same Y1 width), Y2-Y3 beside Y1-Y3 (same Y3 height), the 3-D view top right;
    # the figure is as tall as those panels need at this width, plus labels, colour bar and legend
    ext = np.maximum(np.ptp(Y, axis=0), 1e-9 * extent)
    panels_h = (width - 0.9) * (ext[1] + ext[2]) / (ext[0] + ext[1])
    fig = new_figure(width, float(np.clip(panels_h + 1.6, 0.4 * width, 1.3 * width)))
    gs = fig.add_gridspec(2, 2, width_ratios=[ext[0], ext[1]], height_ratios=[ext[1], ext[2]])
    cells = {(0, 1): gs[0, 0], (0, 2): gs[1, 0], (1, 2): gs[1, 1]}
    axs = [fig.add_subplot(cells[p]) for p in PANELS]
    s_pts = marker_size(N)
    cmap = density_cmap()
    lo3, hi3 = Y.min(axis=0), Y.max(axis=0)
    L, l_loc = 0.35 * extent, 0.12 * extent
    for ax, (a, b) in zip(axs, PANELS):
        d = density(Y[:, [a, b]])
        order = np.argsort(d, kind="stable")
        sc = ax.scatter(Y[order, a], Y[order, b], c=d[order], cmap=cmap, norm=Normalize(0, 1), s=s_pts,
                        linewidths=0, rasterized=rasterize_for(N), zorder=1)
        sc.set_gid(f"fig2a:points:Y{a + 1}Y{b + 1}")
        data_limits(ax, Y[:, a], Y[:, b])
        plane_trace(ax, tan, (a, b), Y, zorder=2)
        data_limits(ax, Y[:, a], Y[:, b])  # the trace runs past the data: the panel spans the data
        lo, hi = lo3[[a, b]], hi3[[a, b]]
        for vec, col, lab in ((S, S_COLOUR, "S"), (V, V_COLOUR, "V")):
            v2 = vec[[a, b]]
            # every arrow stays inside the data's box (and its panel), however the direction projects
            Lv = min(L, 0.85 * reach_in_box(o[[a, b]], v2, lo, hi))
            arrow(ax, o[[a, b]], Lv * v2, color=col, label=lab, lw=1.8, gid=f"fig2a:{lab}", zorder=7)
        for i in local:  # named by the legend's colours: in a panel s_i and v_i may point alike
            s3, v3, _ = tan.drawn_local_frame(i)
            for vec, col, name in ((s3, S_COLOUR, "s_i"), (v3, V_COLOUR, "v_i")):
                d2 = vec[[a, b]]
                if np.linalg.norm(d2) > 1e-6:  # its direction in this panel (the frame lives in all dims of Y)
                    arrow(ax, Y[i, [a, b]], l_loc * d2 / np.linalg.norm(d2), color=col, lw=0.8, head=5,
                          gid=f"fig2a:{name}", zorder=5)
        _trajectory(ax, Y[traj][:, [a, b]])
        ax.set_xlabel(f"Y{a + 1} {ARBITRARY}")
        ax.set_ylabel(f"Y{b + 1} {ARBITRARY}")
        ax.set_aspect("equal", adjustable="box")
    handles = [Line2D([], [], color="k", ls=":", label="zero-velocity plane"),
               Line2D([], [], color=ORIGINAL, marker=">", ms=4, label="example trajectory"),
               Line2D([], [], color=S_COLOUR, lw=1.8, label="shape S; thin: local s"),
               Line2D([], [], color=V_COLOUR, lw=1.8, label="velocity V; thin: local v")]
    if one_column(width):  # a 3-D view an inch wide says nothing: the legend takes its cell
        ax3 = fig.add_subplot(gs[0, 1])
        ax3.set_axis_off()
        ax3.legend(handles=handles, loc="center", frameon=False).set_gid("fig2a:legend")
    else:
        ax3 = fig.add_subplot(gs[0, 1], projection="3d")
        _panel3d(ax3, Y, dens3, tan, o, S, V, L, traj, view3d, cmap)
        legend_below(fig, handles, gid="fig2a:legend")
    cb = fig.colorbar(_mappable(cmap), ax=[*axs, ax3], location="bottom", shrink=0.6, aspect=40, pad=0.02,
                      ticks=[0, 0.25, 0.5, 0.75, 1])
    cb.set_label("local density of the frames (rank in each panel: 0 sparsest, 1 densest)")
    cb.ax.set_gid("fig2a:colourbar")
    fig.suptitle("The speech manifold in the first three dimensions of Y")
    _trim_height(fig, [[axs[0]], [axs[1], axs[2]]])
    fig.lipspace.update(local_frames=local, trajectory_frames=traj)
    return fig


def _trajectory(ax, p):
    """The example trajectory (n, 2) as a black line above the points, with arrowheads giving its direction."""
    line, = ax.plot(p[:, 0], p[:, 1], "-", color=ORIGINAL, lw=0.9, zorder=6, path_effects=halo(1.8))
    line.set_gid("fig2a:trajectory")
    n = len(p)
    for k in np.linspace(0.2 * n, n - 2, N_DIRECTION_MARKS).astype(int):
        k = int(np.clip(k, 0, n - 2))
        if np.linalg.norm(p[k + 1] - p[k]) > 0:
            ax.annotate("", xy=p[k + 1], xytext=p[k], zorder=6,
                        arrowprops=dict(arrowstyle="-|>,head_length=0.45,head_width=0.22", color=ORIGINAL, lw=0.9,
                                        shrinkA=0, shrinkB=0)).set_gid("fig2a:trajectory:direction")


def _trim_height(fig, rows, *, passes: int = 3) -> None:
    """Shorten the figure by the height its equal-aspect panels leave empty in their rows (the layout gives
    each row a cell; a panel of wide data fills the cell's width but not its height), keeping the width."""
    for _ in range(passes):
        fig.draw_without_rendering()
        slack = 0.0
        for row in rows:
            cell = max(ax.get_position(original=True).height for ax in row)
            used = max(ax.get_position(original=False).height for ax in row)
            slack += max(cell - used, 0.0)
        if slack < 0.01:
            return
        w, h = fig.get_size_inches()
        fig.set_size_inches(w, max(h * (1.0 - 0.9 * slack), 0.3 * w))


def _panel3d(ax, Y, dens, tan, o, S, V, L, traj, view, cmap):
    # drawn in the order given (not mplot3d's depth sort, which buried the arrows and the trajectory in the cloud):
    # the plane, the points, then the trajectory, the arrows and their labels above them
    ax.computed_zorder = False
    w = np.cross(V, S)
    d = Y - o
    gu = np.linspace(*np.quantile(d @ S, [0.0, 1.0]), 24)
    gw = np.linspace(*np.quantile(d @ w, [0.0, 1.0]), 24)
    P = o + gu[:, None, None] * S + gw[None, :, None] * w
    # the zero-velocity plane: a translucent patch over the data's extent in the plane, cells outside the
    # axes' limits hidden (mplot3d does not clip)
    ax.plot_surface(P[..., 0], P[..., 1], P[..., 2], color="0.5", alpha=0.18, linewidth=0, shade=False,
                    axlim_clip=True, zorder=0)
    order = np.argsort(dens, kind="stable")
    sc = ax.scatter(Y[order, 0], Y[order, 1], Y[order, 2], c=dens[order], cmap=cmap, norm=Normalize(0, 1),
                    s=marker_size(len(Y)) * 0.7, linewidths=0, depthshade=False, rasterized=True, zorder=1)
    sc.set_gid("fig2a:points:3d")
    lo, hi = Y.min(axis=0), Y.max(axis=0)
    p = Y[traj]
    ax.plot(p[:, 0], p[:, 1], p[:, 2], color=ORIGINAL, lw=1.0, zorder=4, path_effects=halo(1.8))
    ax.quiver(p[-2, 0], p[-2, 1], p[-2, 2], *(p[-1] - p[-2]), color=ORIGINAL, arrow_length_ratio=3.0, zorder=4)
    for vec, col, lab in ((S, S_COLOUR, "S"), (V, V_COLOUR, "V")):
        # mplot3d does not clip: an arrow leaving the box runs over the tick labels, so each arrow
        # (and its label) stops inside the data's box
        Lv = min(L, 0.85 * reach_in_box(o, vec, lo, hi))
        ax.quiver(*o, *(Lv * vec), color=col, linewidth=1.8, arrow_length_ratio=0.15, zorder=5)
        ax.text(*(o + 1.1 * Lv * vec), lab, color=col, fontweight="bold", zorder=6, path_effects=halo())
    for setter, name in ((ax.set_xlabel, "Y1"), (ax.set_ylabel, "Y2"), (ax.set_zlabel, "Y3")):
        setter(name, labelpad=1)
    ax.set_title(f"Y1-Y3 {ARBITRARY}", pad=0)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):  # few ticks: their labels never meet the axis labels
        axis.set_major_locator(MaxNLocator(3))
    # mplot3d's labels lie outside what the layout reserves: a smaller box keeps them inside the figure
    ax.set_box_aspect(tuple(np.maximum(hi - lo, 1e-9)), zoom=0.78)
    ax.view_init(elev=view[0], azim=view[1])
    ax.tick_params(labelsize=font_pt(-1.5), pad=-1)


def _mappable(cmap, norm=None):
    from matplotlib.cm import ScalarMappable

    sm = ScalarMappable(norm=norm or Normalize(0, 1), cmap=cmap)
    sm.set_array([])
    return sm
