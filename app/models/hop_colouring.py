"""Hop distance colouring (the paper's Fig. 2b): the frames by signed hops from a state, within a horizon.

One colour per whole hop: the future hemisphere in :data:`app.models.colour_maps.FUTURE_CMAP`
(near = darkest), the past one in :data:`app.models.colour_maps.PAST_CMAP`; frames beyond the
horizon are dimmed, unreachable ones grey. Qt-free.
"""
from __future__ import annotations

import numpy as np

from app.models.colour_maps import FUTURE_CMAP, OUTSIDE_RGB, PAST_CMAP, UNREACHABLE_RGB, Coloring, colormap_rgb

__all__ = ["hop_table", "hemisphere_coloring"]


def hop_table(max_hops: int, direction: str) -> tuple[np.ndarray, float, float]:
    """The discrete colour scale of signed hop distances.

    One colour per whole hop: past hops ``-max_hops..-1`` in :data:`PAST_CMAP` (far ->
    near), 0 (the state itself, the future's darkest), future hops ``1..max_hops`` in
    :data:`FUTURE_CMAP` (near -> far). Only the sides of ``direction`` are present.

    Returns
    -------
    table : ndarray of shape (n, 3) float32
        Row j colours the value ``lo + 0.5 + j``.
    lo, hi : float
        The scale's range: each whole hop sits in the middle of its band.
    """
    H = max(int(max_hops), 0)
    t = np.linspace(0.0, 1.0, H + 1) if H > 0 else np.array([0.0])
    fut = colormap_rgb(FUTURE_CMAP, t)                 # 0, 1, ..., H
    past = colormap_rgb(PAST_CMAP, t)[1:][::-1]        # -H, ..., -1
    if direction == "future":
        table, lo = fut, -0.5
    elif direction == "past":
        table, lo = np.vstack([past, fut[:1]]), -H - 0.5
    elif direction == "both":
        table, lo = np.vstack([past, fut]), -H - 0.5
    else:
        raise ValueError(f"direction must be 'future', 'past' or 'both', got {direction!r}")
    return table.astype(np.float32), float(lo), float(lo + len(table))


def hemisphere_coloring(manifold, state: int, direction: str, horizon_ms=None, *, cloud=None):
    """Colours of the frames by signed hop distance from ``state`` within ``horizon_ms``.

    ``horizon_ms=None`` means no horizon (every reachable state). Frames outside the
    horizon get :data:`OUTSIDE_RGB` (value NaN), unreachable ones :data:`UNREACHABLE_RGB`.
    With ``cloud`` (an :class:`app.models.lod.CloudDetail`) one colour per drawn point: its
    group's state's, exactly its frames' colour; the readout still counts frames.
    Returns a :class:`app.models.colour_maps.Coloring`.
    """
    from engine.graph.hemispheres import hemisphere, horizon_hops

    g = manifold.states_
    rate = float(manifold.corpus_.rate)
    H = None if horizon_ms is None else horizon_hops(float(horizon_ms) / 1000.0, rate)
    if cloud is None or cloud.whole:
        hem = hemisphere(g, state, g.labels_ if cloud is None else cloud.state, direction=direction, max_hops=H)
    else:
        hem = hemisphere(g, state, cloud.state, direction=direction, max_hops=H, weights=cloud.sizes)
    scale = hem.reach if H is None else H
    table, lo, hi = hop_table(scale, direction)
    v = hem.hops
    idx = np.clip(np.floor(np.nan_to_num(v, nan=0.0) - lo).astype(np.int64), 0, len(table) - 1)
    rgb = table[idx]
    # outside: reachable but beyond the horizon -> dimmed; unreachable -> grey
    rgb[~hem.inside] = OUTSIDE_RGB
    rgb[~hem.reachable] = UNREACHABLE_RGB
    ticks = np.arange(int(np.ceil(lo)), int(np.floor(hi)) + 1)
    step = max(1, int(np.ceil(len(ticks) / 12)))  # at most ~12 labelled ticks, always whole hops
    ticks = ticks[(ticks % step) == 0]
    names = {"future": "future hops", "past": "past hops (−)", "both": "past (−) / future (+) hops"}
    sides = {"future": "future", "past": "past", "both": "past and future"}
    if H is None:
        within = "reachable"
    else:
        within = f"within {float(horizon_ms):.0f} ms ({H} hop{'s' if H != 1 else ''} at {rate:g} frames/s)"
    total = len(v) if hem.weights is None else int(np.sum(hem.weights))
    readout = (f"{sides[direction]} {within}: {100 * hem.fraction_inside:.1f}% of frames "
               f"({hem.n_inside:,}/{total:,})")
    legend = [("beyond the horizon", OUTSIDE_RGB)] if H is not None else []
    legend.append(("unreachable", UNREACHABLE_RGB))
    return Coloring(rgb.astype(np.float32), v, table, (lo, hi), names[direction], legend, ticks,
                    [str(abs(int(t))) if direction != "both" else f"{int(t):+d}".replace("+0", "0")
                     for t in ticks], readout)
