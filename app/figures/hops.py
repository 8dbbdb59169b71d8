"""Paper fig. 2(b): directed geodesic (hop) distances on the state graph from three seed states."""
from __future__ import annotations

import numpy as np
from matplotlib.colors import Normalize
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from app.figures.colours import UNREACHABLE, future_cmap
from app.figures.style import (
    arrow,
    data_limits,
    font_pt,
    frame_sv,
    journal,
    legend_below,
    marker_size,
    new_figure,
    one_column,
    rasterize_for,
    require_fitted,
    state_sv,
)

__all__ = ["make_fig2b", "choose_seed_states", "state_signed_velocity"]

#: length of a seed's arrows to its near future, and half the past | future line, as fractions of the panel
ARROW_FRACTION = 0.18
BOUNDARY_HALF_FRACTION = 0.22


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
def make_fig2b(manifold, *, states=None, near_hops: int = 3, width=None, palette=None):
    """Fig. 2(b): directed geodesic (hop) distances from three states.

    Drawn in the (S, V) plane of the manifold (x: the opening, y: its velocity read on
    the manifold, :func:`app.figures.style.frame_sv`), where the zero-velocity plane is the
    dotted line V = 0, opening above it, closing below. Every frame takes the hop distance
    of its state from the seed (``states_.future``) in the window's future-hemisphere map
    (:func:`app.figures.colours.future_cmap`: dark = the seed's next states, light = the
    farthest); frames of states the seed cannot reach are open grey circles. Arrows point
    from the seed to the mean of its near future (states 1..``near_hops`` hops away), one
    per side of the zero-velocity plane that holds at least a fifth of that near future (a
    zero-velocity seed has two); the dashed line through the seed, perpendicular to the
    direction from the near past (``states_.past``) to the near future, divides past and
    future. Arrows and the dashed line are sized in each panel's own proportions (S and V
    have different units), and each axis spans the frames it shows, nothing more. Every
    mark is named in the legend below the panels.

    Parameters
    ----------
    states : dict or sequence of 3 ints, optional
        Seed states (opening, zero velocity, closing); default :func:`choose_seed_states`.
    palette : app.models.palette.SessionPalette, optional
        Accepted like every figure's (the figure has no categories).
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
    P = frame_sv(manifold)
    N = len(P)
    labels = np.asarray(st.labels_)
    Pc = state_sv(manifold)
    msv = Pc[:, 1]
    dists = {name: np.asarray(st.future(s), dtype=np.float64) for name, s in seeds.items()}
    dmax = max(float(d[np.isfinite(d)].max()) for d in dists.values())
    norm = Normalize(0.0, max(dmax, 1.0))
    cmap = future_cmap()
    narrow = one_column(width)  # one column: the seeds' panels stacked
    fig = new_figure(width, (len(seeds) * 0.5 * width + 1.1) if narrow else width / 3 + 1.1)
    grid = fig.subplots(len(seeds), 1, sharex=True, sharey=True, squeeze=False) if narrow else \
        fig.subplots(1, len(seeds), sharex=True, sharey=True, squeeze=False)
    axs = grid.ravel()
    ms = marker_size(N)
    # S and V have different units: directions and lengths are taken in each axis's share of the data's range
    rng = np.maximum(np.ptp(P, axis=0), 1e-12)
    info = {}
    for ax, (name, s) in zip(axs, seeds.items()):
        d_state = dists[name]
        d = d_state[labels]
        fin = np.isfinite(d)
        un = ax.scatter(P[~fin, 0], P[~fin, 1], s=ms * 1.6, facecolors="none", edgecolors=[UNREACHABLE],
                        linewidths=0.4, rasterized=rasterize_for(N), zorder=1)
        un.set_gid(f"fig2b:unreachable:{name}")
        order = np.flatnonzero(fin)[np.argsort(-d[fin], kind="stable")]   # far first, near on top
        sc = ax.scatter(P[order, 0], P[order, 1], c=d[order], cmap=cmap, norm=norm, s=ms, linewidths=0,
                        rasterized=rasterize_for(N), zorder=2)
        sc.set_gid(f"fig2b:distance:{name}")
        sc.lipspace_frames = order
        data_limits(ax, P[:, 0], P[:, 1])
        ax.axhline(0.0, color="k", ls=":", lw=1.0, zorder=3)
        near = np.flatnonzero((d_state >= 1) & (d_state <= near_hops))
        dirs = []
        for side in (near[msv[near] >= 0], near[msv[near] < 0]):
            if len(near) and len(side) >= 0.2 * len(near):
                vec = (Pc[side].mean(axis=0) - Pc[s]) / rng
                nv = np.linalg.norm(vec)
                if nv > 0:
                    dirs.append(vec / nv)
                    arrow(ax, Pc[s], ARROW_FRACTION * rng * vec / nv, color="k", lw=1.6, gid=f"fig2b:future:{name}")
        # past | future: the dashed line through the seed perpendicular to the direction from its near past
        # (1..near_hops hops over the reversed graph) to its near future, in the panel's proportions
        d_past = np.asarray(st.past(s), dtype=np.float64)
        past = np.flatnonzero((d_past >= 1) & (d_past <= near_hops))
        m = (Pc[near].mean(axis=0) - Pc[past].mean(axis=0)) / rng if len(near) and len(past) else \
            (np.mean(dirs, axis=0) if dirs else np.zeros(2))
        if np.linalg.norm(m) > 1e-9:
            m = m / np.linalg.norm(m)
            perp = np.array([-m[1], m[0]])
            seg = Pc[s] + np.outer([-BOUNDARY_HALF_FRACTION, BOUNDARY_HALF_FRACTION], perp * rng)
            ax.plot(seg[:, 0], seg[:, 1], "k--", lw=1.0, zorder=4, gid=f"fig2b:past-future:{name}")
        ax.plot(*Pc[s], marker="*", ms=11, mfc="white", mec="k", mew=1.0, zorder=8, gid=f"fig2b:seed:{name}")
        data_limits(ax, P[:, 0], P[:, 1])
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
    handles = [Line2D([], [], ls="none", marker="*", ms=8, mfc="white", mec="k", label="seed state"),
               Line2D([], [], color="k", lw=1.6, marker=">", ms=4, label=f"to its near future (1-{near_hops} hops)"),
               Line2D([], [], color="k", ls="--", lw=1.0, label="past | future boundary"),
               Line2D([], [], color="k", ls=":", lw=1.0, label="zero velocity (V = 0)"),
               Line2D([], [], ls="none", marker="o", ms=3.5, mfc="none", mec=UNREACHABLE, label="unreachable")]
    legend_below(fig, handles, ncol=2 if narrow else 3, gid="fig2b:legend")
    cb = fig.colorbar(_mappable(cmap, norm), ax=axs, shrink=0.8, location="bottom" if narrow else "right")
    cb.set_label("hops from the seed state (future)")
    cb.locator = MaxNLocator(integer=True)
    cb.update_ticks()
    fig.suptitle("Directed geodesic distances on the manifold (future hemisphere)")
    fig.lipspace.update(seeds=seeds, info=info, hop_norm=(norm.vmin, norm.vmax))
    return fig


def _mappable(cmap, norm):
    from matplotlib.cm import ScalarMappable

    sm = ScalarMappable(norm=norm, cmap=cmap)
    sm.set_array([])
    return sm
