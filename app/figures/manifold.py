"""Figures of the manifold's structure (paper figs 2a, 2b) and the tangent classes."""
from __future__ import annotations

import numpy as np
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D

from app.figures.style import (
    ARBITRARY,
    CLASS_COLOURS,
    CMAP,
    CMAP_NEAR,
    ORIGINAL,
    S_COLOUR,
    UNREACHABLE,
    V_COLOUR,
    arrow,
    below,
    density,
    font_pt,
    frame_sv,
    journal,
    legend_below,
    marker_size,
    new_figure,
    one_column,
    plane_trace,
    rasterize_for,
    require_fitted,
    state_sv,
    sv_basis,
    y3,
)

__all__ = ["make_fig2a", "make_fig2b", "make_classes", "choose_seed_states", "example_segment"]

PANELS = ((0, 1), (0, 2), (1, 2))


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
def make_fig2a(manifold, *, utterance=None, n_local: int = 4, n_traj: int = 45, view3d=(22, -60), width=None):
    """Fig. 2(a): the manifold in the first three dims of Y.

    Three 2-D projections (Y1–Y2, Y1–Y3, Y2–Y3; the paper's caption speaks of density
    "in each projection", and flat panels export cleanly to SVG/PDF) and a 3-D view
    (mplot3d, ``view3d`` = (elevation, azimuth) in degrees). Points are coloured by
    their density in that projection (in 3-D for the 3-D view), red (dense) → blue
    (sparse), densest drawn last. Arrows: global S and V from the plane point
    (thick), local s_i and v_i at ``n_local`` frames spread along S (thin); the
    zero-velocity plane's trace dotted (a translucent patch in 3-D); an example
    trajectory (``n_traj`` frames of ``utterance``) as black arrows. The panels' sizes
    follow the data's extents and the figure's height follows them, so the equal-aspect
    panels fill their cells; the density colour bar and the legend lie below them. On one
    journal column (:func:`app.figures.style.one_column`) the legend takes the 3-D view's
    cell: a 3-D view an inch wide shows nothing the projections do not.
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
    L, l_loc = 0.35 * extent, 0.12 * extent
    for ax, (a, b) in zip(axs, PANELS):
        d = density(Y[:, [a, b]])
        order = np.argsort(d, kind="stable")
        sc = ax.scatter(Y[order, a], Y[order, b], c=d[order], cmap=CMAP, norm=Normalize(0, 1), s=s_pts,
                        linewidths=0, rasterized=rasterize_for(N))
        sc.set_gid(f"fig2a:points:Y{a + 1}Y{b + 1}")
        plane_trace(ax, tan, (a, b), Y)
        arrow(ax, o[[a, b]], L * S[[a, b]], color=S_COLOUR, label="S", lw=1.8, gid="fig2a:S")
        arrow(ax, o[[a, b]], L * V[[a, b]], color=V_COLOUR, label="V", lw=1.8, gid="fig2a:V")
        for i in local:  # named by the legend's colours: in a panel s_i and v_i may point alike
            s3, v3, _ = tan.drawn_local_frame(i)
            for vec, col, name in ((s3, S_COLOUR, "s_i"), (v3, V_COLOUR, "v_i")):
                d2 = vec[[a, b]]
                if np.linalg.norm(d2) > 1e-6:  # its direction in this panel (the frame lives in all dims of Y)
                    arrow(ax, Y[i, [a, b]], l_loc * d2 / np.linalg.norm(d2), color=col, lw=0.8, head=5,
                          gid=f"fig2a:{name}")
        p = Y[traj[::2]][:, [a, b]]
        q = ax.quiver(p[:-1, 0], p[:-1, 1], np.diff(p[:, 0]), np.diff(p[:, 1]), angles="xy",
                      scale_units="xy", scale=1, color=ORIGINAL, width=0.004, headwidth=4, headlength=5,
                      headaxislength=4.5, zorder=5)
        q.set_gid("fig2a:trajectory")
        ax.set_xlabel(f"$Y_{a + 1}$ {ARBITRARY}")
        ax.set_ylabel(f"$Y_{b + 1}$ {ARBITRARY}")
        ax.set_aspect("equal", adjustable="box")
    handles = [Line2D([], [], color="k", ls=":", label="zero-velocity plane"),
               Line2D([], [], color=ORIGINAL, marker=">", label="example trajectory"),
               Line2D([], [], color=S_COLOUR, label="shape S, $s_i$"),
               Line2D([], [], color=V_COLOUR, label="velocity V, $v_i$")]
    if one_column(width):  # a 3-D view an inch wide says nothing: the legend takes its cell
        ax3 = fig.add_subplot(gs[0, 1])
        ax3.set_axis_off()
        ax3.legend(handles=handles, loc="center", frameon=False).set_gid("fig2a:legend")
    else:
        ax3 = fig.add_subplot(gs[0, 1], projection="3d")
        _panel3d(ax3, Y, dens3, tan, o, S, V, L, traj, view3d)
        legend_below(fig, handles, gid="fig2a:legend")
    cb = fig.colorbar(_mappable(), ax=[*axs, ax3], location="bottom", shrink=0.6, aspect=40, pad=0.02,
                      ticks=[0, 0.25, 0.5, 0.75, 1])
    cb.set_label("local density of the frames (rank in each panel: 0 sparsest, 1 densest)")
    cb.ax.set_gid("fig2a:colourbar")
    fig.suptitle("The speech manifold in the first three dimensions of Y")
    _trim_height(fig, [[axs[0]], [axs[1], axs[2]]])
    fig.lipspace.update(local_frames=local, trajectory_frames=traj)
    return fig


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


def _panel3d(ax, Y, dens, tan, o, S, V, L, traj, view):
    order = np.argsort(dens, kind="stable")
    sc = ax.scatter(Y[order, 0], Y[order, 1], Y[order, 2], c=dens[order], cmap=CMAP, norm=Normalize(0, 1),
                    s=marker_size(len(Y)) * 0.7, linewidths=0, depthshade=False, rasterized=True)
    sc.set_gid("fig2a:points:3d")
    # the zero-velocity plane: a translucent patch over the data's extent in the plane, cells
    # outside the axes' limits hidden (mplot3d does not clip)
    w = np.cross(V, S)
    d = Y - o
    gu = np.linspace(*np.quantile(d @ S, [0.0, 1.0]), 24)
    gw = np.linspace(*np.quantile(d @ w, [0.0, 1.0]), 24)
    P = o + gu[:, None, None] * S + gw[None, :, None] * w
    ax.plot_surface(P[..., 0], P[..., 1], P[..., 2], color="0.5", alpha=0.18, linewidth=0, shade=False,
                    axlim_clip=True)
    lo, hi = Y.min(axis=0), Y.max(axis=0)
    for vec, col, lab in ((S, S_COLOUR, "S"), (V, V_COLOUR, "V")):
        # mplot3d does not clip: an arrow leaving the box runs over the tick labels, so each arrow
        # (and its label) stops inside the data's box
        Lv = min(L, 0.85 * _reach_in_box(o, vec, lo, hi))
        ax.quiver(*o, *(Lv * vec), color=col, linewidth=1.8, arrow_length_ratio=0.15)
        ax.text(*(o + 1.08 * Lv * vec), lab, color=col, fontweight="bold")
    p = Y[traj]
    ax.plot(p[:, 0], p[:, 1], p[:, 2], color=ORIGINAL, lw=1.0)
    ax.quiver(p[-2, 0], p[-2, 1], p[-2, 2], *(p[-1] - p[-2]), color=ORIGINAL, arrow_length_ratio=3.0)
    ax.set_xlabel("$Y_1$", labelpad=-6)
    ax.set_ylabel("$Y_2$", labelpad=-6)
    ax.set_zlabel("$Y_3$", labelpad=-6)
    ax.set_title(f"$Y_1$-$Y_3$ {ARBITRARY}", pad=0)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    # mplot3d's labels lie outside what the layout reserves: a smaller box keeps them inside the figure
    ax.set_box_aspect(tuple(np.maximum(hi - lo, 1e-9)), zoom=0.8)
    ax.view_init(elev=view[0], azim=view[1])
    ax.tick_params(labelsize=font_pt(-1.5), pad=-2)


def _reach_in_box(o, vec, lo, hi) -> float:
    """How far from ``o`` along ``vec`` the box [lo, hi] extends (inf if unbounded or ``o`` is outside it)."""
    o, vec = np.asarray(o, float), np.asarray(vec, float)
    if np.any(o < lo) or np.any(o > hi):
        return float("inf")
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(vec > 0, (hi - o) / vec, np.where(vec < 0, (lo - o) / vec, np.inf))
    return float(np.min(t))


def _mappable(cmap=CMAP, norm=None):
    from matplotlib.cm import ScalarMappable

    sm = ScalarMappable(norm=norm or Normalize(0, 1), cmap=cmap)
    sm.set_array([])
    return sm


def state_signed_velocity(manifold) -> np.ndarray:
    """Mean opening velocity (the V coordinate) of each state's frames, (K,)."""
    return state_sv(manifold)[:, 1]


def choose_seed_states(manifold) -> dict:
    """Opening, zero-velocity and closing states for fig. 2(b), chosen automatically.

    Candidates are well-populated states (at least the median membership) in the
    largest strongly connected component. Opening: among candidates in the top decile
    of mean opening velocity (V), the one whose mean opening (S) is nearest the median
    of all frames (mid-opening, not an extreme); closing: the same in the bottom
    decile; zero-velocity: the same among the fifth of candidates slowest.
    Returns ``{"opening": k, "zero velocity": k, "closing": k}``.
    """
    st = manifold.states_
    K = st.centroids_.shape[0]
    Psv = state_sv(manifold)
    msv = Psv[:, 1]
    cnt = np.bincount(np.asarray(st.labels_), minlength=K)
    ok = cnt >= max(1, np.median(cnt[cnt > 0]))
    scc = getattr(st, "scc_labels_", None)
    if scc is not None:
        scc = np.asarray(scc)
        big = np.bincount(scc).argmax()
        if (ok & (scc == big)).sum() >= 3:
            ok &= scc == big
    cand = np.flatnonzero(ok)
    # representative rather than extreme: among the candidates in the top / bottom decile of
    # opening velocity (and the lowest quintile of |velocity|), the state nearest the median
    # opening of all frames
    s_state = Psv[:, 0]
    s_mid = float(np.median(frame_sv(manifold)[:, 0]))
    v = msv[cand]

    def nearest_mid(sel):
        pool = cand[sel] if sel.any() else cand
        return int(pool[np.argmin(np.abs(s_state[pool] - s_mid))])

    return {"opening": nearest_mid(v >= np.quantile(v, 0.9)),
            "zero velocity": nearest_mid(np.abs(v) <= np.quantile(np.abs(v), 0.2)),
            "closing": nearest_mid(v <= np.quantile(v, 0.1))}


@journal
def make_fig2b(manifold, *, states=None, near_hops: int = 3, width=None):
    """Fig. 2(b): directed geodesic (hop) distances from three states.

    Drawn in the (S, V) plane of the manifold (x: the opening, y: its velocity read on
    the manifold, :func:`frame_sv`), where the zero-velocity plane is the dotted line
    V = 0, opening above it, closing below. Every frame takes the hop
    distance of its state from the seed (``states_.future``): red (near) → blue (far),
    unreachable grey. Arrows point from the seed to the mean of its near future
    (states 1..``near_hops`` hops away), one per side of the zero-velocity plane that
    holds at least a fifth of that near future (a zero-velocity seed has two); the
    dashed line through the seed, perpendicular to the direction from the near past
    (``states_.past``) to the near future, delineates past and future.

    Parameters
    ----------
    states : dict or sequence of 3 ints, optional
        Seed states (opening, zero velocity, closing); default
        :func:`choose_seed_states`.
    """
    require_fitted(manifold, "tangent_", "states_")
    st, tan = manifold.states_, manifold.tangent_
    if states is None:
        seeds = choose_seed_states(manifold)
    elif isinstance(states, dict):
        seeds = {str(k): int(v) for k, v in states.items()}
    else:
        seeds = dict(zip(("opening", "zero velocity", "closing"), (int(s) for s in states)))
    K = st.centroids_.shape[0]
    for name, s in seeds.items():
        if not 0 <= s < K:
            raise ValueError(f"seed state {s} ({name}) out of range: the state graph has {K} states (0..{K - 1})")
    Y = y3(manifold)
    P = frame_sv(manifold)
    labels = np.asarray(st.labels_)
    Pc = state_sv(manifold)
    msv = Pc[:, 1]
    dists = {name: np.asarray(st.future(s), dtype=np.float64) for name, s in seeds.items()}
    dmax = max(float(d[np.isfinite(d)].max()) for d in dists.values())
    norm = Normalize(0.0, max(dmax, 1.0))
    narrow = one_column(width)  # one column: the seeds' panels stacked
    fig = new_figure(width, (len(seeds) * 0.5 * width + 0.9) if narrow else width / 3 + 0.9)
    grid = fig.subplots(len(seeds), 1, sharex=True, sharey=True, squeeze=False) if narrow else \
        fig.subplots(1, len(seeds), sharex=True, sharey=True, squeeze=False)
    axs = grid.ravel()
    ms = marker_size(len(Y))
    extent = float(np.ptp(P, axis=0).max()) or 1.0
    info = {}
    for ax, (name, s) in zip(axs, seeds.items()):
        d_state = dists[name]
        d = d_state[labels]
        fin = np.isfinite(d)
        un = ax.scatter(P[~fin, 0], P[~fin, 1], s=ms, c=UNREACHABLE, linewidths=0, rasterized=rasterize_for(len(Y)))
        un.set_gid(f"fig2b:unreachable:{name}")
        order = np.flatnonzero(fin)[np.argsort(-d[fin], kind="stable")]   # far first, near on top
        sc = ax.scatter(P[order, 0], P[order, 1], c=d[order], cmap=CMAP_NEAR, norm=norm, s=ms, linewidths=0,
                        rasterized=rasterize_for(len(Y)))
        sc.set_gid(f"fig2b:distance:{name}")
        sc.lipspace_frames = order
        ax.axhline(0.0, color="k", ls=":", lw=1.2)
        ax.plot(*Pc[s], marker="*", ms=14, mfc="white", mec="k", mew=1.2, zorder=6, gid=f"fig2b:seed:{name}")
        near = np.flatnonzero((d_state >= 1) & (d_state <= near_hops))
        dirs = []
        for side in (near[msv[near] >= 0], near[msv[near] < 0]):
            if len(near) and len(side) >= 0.2 * len(near):
                vec = Pc[side].mean(axis=0) - Pc[s]
                nv = np.linalg.norm(vec)
                if nv > 0:
                    dirs.append(vec / nv)
                    arrow(ax, Pc[s], 0.18 * extent * vec / nv, color="k", lw=2.0, gid=f"fig2b:future:{name}")
        # past | future: the dashed line through the seed perpendicular to the direction
        # from its near past (1..near_hops hops over the reversed graph) to its near future
        d_past = np.asarray(st.past(s), dtype=np.float64)
        past = np.flatnonzero((d_past >= 1) & (d_past <= near_hops))
        m = Pc[near].mean(axis=0) - Pc[past].mean(axis=0) if len(near) and len(past) else \
            (np.mean(dirs, axis=0) if dirs else np.zeros(2))
        if np.linalg.norm(m) > 1e-9 * extent:
            m = m / np.linalg.norm(m)
            perp = np.array([-m[1], m[0]])
            seg = Pc[s] + np.outer([-0.25 * extent, 0.25 * extent], perp)
            ax.plot(seg[:, 0], seg[:, 1], "k--", lw=1.0, gid=f"fig2b:past-future:{name}")
        reach = int(np.isfinite(d_state).sum())
        ax.set_title(f"{name}: state {s}\n({reach}/{K} states reachable)")
        info[name] = {"state": s, "reachable": reach, "n_future_directions": len(dirs)}
    s_label, v_label = tan.sv_labels()
    if narrow:  # stacked panels: one label for the column, not one per panel
        axs[-1].set_xlabel(s_label)
        fig.supylabel(v_label, fontsize=font_pt())
    else:
        for ax in axs:
            ax.set_xlabel(s_label)
        axs[0].set_ylabel(v_label)
    cb = fig.colorbar(_mappable(CMAP_NEAR, norm), ax=axs, shrink=0.8, location="bottom" if narrow else "right")
    cb.set_label("hops from the state (grey: unreachable)")
    from matplotlib.ticker import MaxNLocator

    cb.locator = MaxNLocator(integer=True)
    cb.update_ticks()
    fig.suptitle("Directed geodesic distances on the manifold (future hemisphere)")
    fig.lipspace.update(seeds=seeds, info=info, hop_norm=(norm.vmin, norm.vmax))
    return fig


@journal
def make_classes(manifold, *, width=None, height: float | None = None):
    """The four tangent classes: proportions (bars) and where they lie in the (S, V) plane.

    Side by side at two-column width, stacked on one column; the classes' legend below.
    """
    require_fitted(manifold, "tangent_")
    tan = manifold.tangent_
    names = list(tan.CLASS_NAMES)
    cls = np.asarray(tan.classes_)
    valid = cls >= 0
    counts = np.bincount(cls[valid], minlength=len(names))[: len(names)]
    frac = counts / max(counts.sum(), 1)
    narrow = one_column(width)
    fig = new_figure(width, height or (1.55 if narrow else 0.45) * width)
    ax, ax2 = fig.subplots(2, 1, height_ratios=(1, 1.3)) if narrow else fig.subplots(1, 2, width_ratios=(1, 1.3))
    bars = ax.bar(np.arange(len(names)), 100 * frac, color=CLASS_COLOURS[: len(names)])
    for patch in bars:
        patch.set_gid("classes:bars")
    for k, f in enumerate(frac):
        ax.annotate(f"{100 * f:.1f}%", xy=(k, 100 * f), xytext=(0, 2), textcoords="offset points",
                    ha="center", fontsize=font_pt(-1))
    ax.set_xticks(np.arange(len(names)), [n.replace("/", "/\n") for n in names])
    ax.set_ylabel("% of frames")
    ax.set_ylim(0, max(100 * frac.max() * 1.2, 1))
    ax.set_title("Tangent classes (frames with a step)")
    truth = _true_agreement(manifold)
    if truth is not None:
        below(ax, f"true aperture: opening {100 * truth.opening:.1f}%, accelerating "
              f"{100 * truth.accelerating:.1f}%\n(trivial rule {100 * truth.trivial_opening:.1f}%, "
              f"{100 * truth.trivial_accelerating:.1f}%)")
    P = frame_sv(manifold)
    sel = np.flatnonzero(valid)
    sel = sel[np.random.default_rng(0).permutation(len(sel))]   # no class hides another
    sc = ax2.scatter(P[sel, 0], P[sel, 1], s=marker_size(len(P)), c=np.asarray(CLASS_COLOURS)[cls[sel]],
                     linewidths=0, rasterized=rasterize_for(len(P)))
    sc.set_gid("classes:points")
    ax2.axhline(0, color="k", ls=":", lw=1.0)
    ax2.set_xlabel(tan.sv_labels()[0])
    ax2.set_ylabel(tan.sv_labels()[1])
    handles = [Line2D([], [], ls="none", marker="o", ms=5, color=CLASS_COLOURS[k], label=n)
               for k, n in enumerate(names)]
    legend_below(fig, handles, gid="classes:legend")
    fig.lipspace.update(proportions=dict(zip(names, frac.tolist())),
                        true_agreement=None if truth is None else truth.opening,
                        opening_on_positive_v=float(np.mean(P[valid & (cls <= 1), 1] > 0))
                        if (valid & (cls <= 1)).any() else float("nan"))
    return fig


def _true_agreement(manifold):
    """The classes against the synthetic talker's true aperture (engine.manifold.class_agreement), or None."""
    lat = getattr(manifold.corpus_, "latent", {}) or {}
    if "aperture" not in lat:
        return None
    from engine.manifold.class_agreement import class_agreement
    from engine.recordings.kinematics import lip_aperture

    tan = manifold.tangent_
    return class_agreement(tan.opening_, tan.accelerating_, lat["aperture"], manifold.corpus_.bounds,
                           measured=lip_aperture(manifold.corpus_))
