"""How the explorer colours the manifold: one palette per meaning, free of Qt and VTK.

* density: blue (low) -> red (high), as the paper's Fig. 2a;
* hop distance (the paper's Fig. 2b) within a time horizon: the future hemisphere in a
  warm family (dark red = next states -> light yellow = the horizon), the past one in a
  cool family (dark blue -> pale blue), on an integer scale of whole hops; states
  outside the horizon are dimmed, unreachable ones grey;
* tangent class: the figure set's four colours;
* phone: one categorical palette for every view (:func:`phone_palette`); a phone filter
  colours only the chosen phones and dims the rest;
* ellipsoids: colours that never reuse a colour the scene already gives a meaning
  (trajectories, path, markers, S and V; :data:`RESERVED_COLOURS`).

While ellipsoids are shown the points are dimmed (:func:`dim`) so the clusters stand out.
"""
from __future__ import annotations

import functools
import json
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Coloring", "CLASS_COLOURS", "CLASS_LABELS", "UNREACHABLE_RGB", "OUTSIDE_RGB", "DENSITY_CMAP",
           "FUTURE_CMAP", "PAST_CMAP", "RESERVED_COLOURS", "ELLIPSOID_COLOURS", "point_colors",
           "hop_table", "hemisphere_coloring", "categorical_palette", "phone_palette",
           "ellipsoid_colors", "dim", "delta_e", "LEGEND_MAX"]

#: the four tangent classes (engine.manifold.tangent classes_ 0..3), as in the figure set
CLASS_COLOURS = ((0.839, 0.153, 0.157), (1.0, 0.596, 0.588), (0.122, 0.310, 0.706), (0.561, 0.722, 1.0))
CLASS_LABELS = ("opening / accelerating", "opening / decelerating", "closing / accelerating",
                "closing / decelerating")
#: frames with no value (unreachable state, no phone, no forward step)
UNREACHABLE_RGB = (0.69, 0.69, 0.69)
#: frames reachable but outside the time horizon, or filtered out: dimmed towards the background
OUTSIDE_RGB = (0.86, 0.86, 0.86)
#: paper: density runs blue (low) -> red (high)
DENSITY_CMAP = "jet"
#: hop distance: near -> far within the horizon, one colour family per hemisphere
FUTURE_CMAP = "YlOrRd_r"
PAST_CMAP = "PuBu_r"
#: how far along each family the colours run (the lightest end is too close to white)
_FAMILY_SPAN = (0.0, 0.78)
#: legends in the 3-D view list at most this many categories
LEGEND_MAX = 16

#: colours the manifold scene already uses for a meaning (app.scene.manifold and the view's markers):
#: original trajectory, synthetic trajectory, state path, S, V, local s_i, v_i, normal, selected, target
RESERVED_COLOURS = {
    "original trajectory": (0.0, 0.0, 0.0), "synthetic trajectory": (1.0, 0.0, 0.0),
    "state path": (1.0, 0.5, 0.0), "S": (0.0, 0.39, 0.0), "V": (0.545, 0.0, 0.545),
    "local s": (0.2, 0.75, 0.2), "local v": (0.85, 0.2, 0.85), "normal": (0.1, 0.45, 0.85),
    "selected": (1.0, 0.85, 0.0), "target": (0.0, 0.8, 0.8),
}
#: ellipsoid colours, in phone-label order of the visible set; each is at least 25 CIELAB units
#: (delta E 1976) from every reserved colour and from each other (checked by a test)
#: (and from the greys of unreachable and dimmed points): brown, teal, pink, navy, olive, periwinkle,
#: lavender, maroon
ELLIPSOID_COLOURS = ((0.55, 0.34, 0.16), (0.0, 0.45, 0.45), (0.95, 0.55, 0.70), (0.12, 0.16, 0.48),
                     (0.60, 0.62, 0.15), (0.55, 0.65, 0.95), (0.70, 0.55, 0.95), (0.5, 0.0, 0.2))


@dataclass
class Coloring:
    """How to colour the manifold's points.

    Attributes
    ----------
    rgb : ndarray of shape (G, 3) float32 in [0, 1]
        One colour per drawn point (G = N while every frame is drawn).
    values : ndarray of shape (G,) float32 or None
        The scalar shown (density, signed hop distance), NaN = no value; None for categories.
    cmap : str, or ndarray of shape (n, 3) of RGB rows for a discrete scale, or None
    clim : (float, float) or None
    title : str
    legend : list of (str, (r, g, b))
        Category colours (class, phone); empty for scalars.
    ticks : ndarray or None
        Values to label on the colour bar (whole hops for hop distance); None lets the bar choose.
    tick_labels : list of str or None
    readout : str
        One line for the status readout (e.g. the fraction inside the horizon).
    """

    rgb: np.ndarray
    values: np.ndarray | None = None
    cmap: object = None
    clim: tuple | None = None
    title: str = ""
    legend: list = field(default_factory=list)
    ticks: np.ndarray | None = None
    tick_labels: list | None = None
    readout: str = ""


# ------------------------------------------------------------------------------ helpers
_TABLE_FILE = "colour_tables.json"  # package data of app.models


@functools.lru_cache(maxsize=1)
def _tables() -> dict:
    from importlib import resources

    return json.loads(resources.files(__package__).joinpath(_TABLE_FILE).read_text(encoding="utf-8"))


@functools.lru_cache(maxsize=None)
def colour_table(name: str) -> np.ndarray:
    """RGB entries (n, 3) float64 of colormap ``name``, read from the shipped ``colour_tables.json``
    (matplotlib's entries, written by :mod:`app.figures.colour_tables`; no matplotlib import here)."""
    tables = _tables()
    if name not in tables:
        raise KeyError(f"no colour table {name!r} in app/models/{_TABLE_FILE}; it has {', '.join(sorted(tables))}")
    table = np.asarray(tables[name], dtype=np.float64)
    table.setflags(write=False)
    return table


def colormap_rgb(name: str, t) -> np.ndarray:
    """Colours (..., 3) of ``t`` in [0, 1] on the 256-entry colormap ``name``, as matplotlib's
    ``colormaps[name](t)`` gives them (entry ``floor(t * 256)``, the last for t = 1)."""
    table = colour_table(name)
    n = table.shape[0]
    idx = np.clip((np.asarray(t, dtype=np.float64) * n).astype(np.int64), 0, n - 1)
    return table[idx]


def _map(values, cmap: str, clim) -> np.ndarray:
    lo, hi = clim
    t = (np.asarray(values, dtype=np.float64) - lo) / (hi - lo if hi > lo else 1.0)
    rgb = colormap_rgb(cmap, np.clip(np.nan_to_num(t, nan=0.0), 0, 1))
    rgb[~np.isfinite(values)] = UNREACHABLE_RGB
    return rgb.astype(np.float32)


def _lab(rgb) -> np.ndarray:
    """sRGB in [0, 1] (..., 3) -> CIELAB (D65)."""
    c = np.asarray(rgb, dtype=np.float64)
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    M = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    xyz = lin @ M.T / np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], -1)


def delta_e(a, b) -> np.ndarray:
    """CIE 1976 colour difference between sRGB colours ``a`` and ``b`` (broadcast)."""
    return np.linalg.norm(_lab(a) - _lab(b), axis=-1)


def dim(rgb, amount: float = 0.7) -> np.ndarray:
    """Colours moved ``amount`` of the way towards :data:`OUTSIDE_RGB` (the background's grey)."""
    rgb = np.asarray(rgb, dtype=np.float32)
    return ((1 - amount) * rgb + amount * np.asarray(OUTSIDE_RGB, np.float32)).astype(np.float32)


def categorical_palette(n: int) -> np.ndarray:
    """``n`` distinguishable RGB colours, shape (n, 3).

    tab20, tab20b and tab20c, each reordered so that consecutive colours differ in hue
    (tab20 stores light/dark pairs side by side), without their greys (grey means "no
    value" and "dimmed" in the explorer), cycled when ``n`` exceeds 54.
    """
    parts = []
    for name, step in (("tab20", 2), ("tab20b", 4), ("tab20c", 4)):
        c = colour_table(name)
        parts.append(np.concatenate([c[k::step] for k in range(step)]))
    base = np.concatenate(parts)
    base = base[np.ptp(base, axis=1) > 0.05]  # drop the greys
    return np.asarray(base[np.arange(n) % len(base)], dtype=np.float32)


def phone_palette(state) -> dict:
    """Colour of each phone label (sorted labels, :func:`categorical_palette`), shared by all views."""
    names = list(state.phone_names)
    return {n: tuple(float(c) for c in col) for n, col in zip(names, categorical_palette(len(names)))}


def ellipsoid_colors(visible) -> dict:
    """Colour of each visible phone's ellipsoid: :data:`ELLIPSOID_COLOURS` in label order."""
    names = sorted(visible)
    return {n: ELLIPSOID_COLOURS[i % len(ELLIPSOID_COLOURS)] for i, n in enumerate(names)}


# ------------------------------------------------------------------------- hop distance
def hop_table(max_hops: int, direction: str) -> tuple[np.ndarray, float, float]:
    """The discrete colour scale of signed hop distances.

    One colour per whole hop: past hops ``-max_hops..-1`` in :data:`PAST_CMAP` (far ->
    near), 0 (the state itself, darkest red), future hops ``1..max_hops`` in
    :data:`FUTURE_CMAP` (near -> far). Only the sides of ``direction`` are present.

    Returns
    -------
    table : ndarray of shape (n, 3) float32
        Row j colours the value ``lo + 0.5 + j``.
    lo, hi : float
        The scale's range: each whole hop sits in the middle of its band.
    """
    H = max(int(max_hops), 0)
    a, b = _FAMILY_SPAN
    t = np.linspace(a, b, H + 1) if H > 0 else np.array([a])
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


def hemisphere_coloring(manifold, state: int, direction: str, horizon_ms=None, *, cloud=None) -> Coloring:
    """Colours of the frames by signed hop distance from ``state`` within ``horizon_ms``.

    ``horizon_ms=None`` means no horizon (every reachable state). Frames outside the
    horizon get :data:`OUTSIDE_RGB` (value NaN), unreachable ones :data:`UNREACHABLE_RGB`.
    With ``cloud`` (an :class:`app.models.lod.CloudDetail`) one colour per drawn point: its
    group's state's, exactly its frames' colour; the readout still counts frames.
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
    return Coloring(rgb.astype(np.float32), v, table, (lo, hi), names[direction], [], ticks,
                    [str(abs(int(t))) if direction != "both" else f"{int(t):+d}".replace("+0", "0")
                     for t in ticks], readout)


# --------------------------------------------------------------------------- every mode
def point_colors(mode: str, manifold, state=None) -> Coloring:
    """Colours of the points the manifold view draws for colour mode ``mode``: one per frame
    while every frame is drawn, else one per group of frames (``state.cloud``, an
    :class:`app.models.lod.CloudDetail`), computed from all the frames it stands for.

    ``state`` (an :class:`app.models.state.AppState`) supplies the selection and hemisphere
    (distance mode), the horizon, the current utterance (utterance mode highlights it),
    the phone filter (phone mode), the shown ellipsoids (points dimmed), the cloud and
    the cached density / phones.
    """
    from app.models.state import COLOR_MODES, AppState

    if state is None:
        state = AppState(manifold)
    c = _mode_colors(mode, manifold, state, COLOR_MODES)
    if state.visible_phones:
        c.rgb = dim(c.rgb)
    return c


def _phone_counts(state):
    """(G, P + 1) csr: frames of each phone code in each drawn point's group (code P: no phone)."""
    import scipy.sparse as sp

    cd, P = state.cloud, len(state.phone_names)
    keys, n = np.unique(cd.group_of * (P + 1) + state.phone_codes, return_counts=True)
    return sp.csr_matrix((n, (keys // (P + 1), keys % (P + 1))), shape=(cd.n_points, P + 1))


def _row_argmax(m) -> np.ndarray:
    """Column of each row's largest entry of a csr matrix with sorted indices (the first on a tie; 0 for
    an empty row), without a Python loop over rows."""
    m.sort_indices()
    n = np.diff(m.indptr)
    out = np.zeros(m.shape[0], np.int64)
    rows = np.flatnonzero(n > 0)
    if rows.size == 0:
        return out
    top = np.maximum.reduceat(m.data, m.indptr[rows])
    row_of = np.repeat(np.arange(m.shape[0]), n)
    at = np.flatnonzero(m.data == top[np.searchsorted(rows, row_of)])
    first = at[np.r_[True, row_of[at][1:] != row_of[at][:-1]]]
    out[row_of[first]] = m.indices[first]
    return out


def _mode_colors(mode, manifold, state, modes) -> Coloring:
    cd = state.cloud
    G = cd.n_points
    if mode == "density":
        v = state.density if cd.whole else cd.density  # a group: the histogram density of its cell
        clim = (float(np.percentile(v, 2)), float(np.percentile(v, 98)))
        return Coloring(_map(v, DENSITY_CMAP, clim), v, DENSITY_CMAP, clim, "log density")
    if mode == "distance":
        if state.state is None:
            v = np.full(G, np.nan, dtype=np.float32)
            return Coloring(np.broadcast_to(np.asarray(UNREACHABLE_RGB, np.float32), (G, 3)).copy(), v, None,
                            None, "hop distance", readout="click a point to colour its hemisphere")
        if state.hemisphere == "off":
            v = np.where(cd.state == state.state, 0.0, np.nan).astype(np.float32)
            rgb = np.where(np.isfinite(v)[:, None], np.asarray(RESERVED_COLOURS["selected"], np.float32),
                           np.asarray(UNREACHABLE_RGB, np.float32)).astype(np.float32)
            return Coloring(rgb, v, None, None, "selected state")
        return hemisphere_coloring(manifold, state.state, state.hemisphere, state.horizon_ms, cloud=cd)
    if mode == "class":
        cls = state.derived("class_points", lambda: cd.plurality(
            np.where(np.asarray(manifold.tangent_.classes_) < 0, 4, manifold.tangent_.classes_), 5))
        pal = np.vstack([np.asarray(CLASS_COLOURS, np.float32), np.asarray(UNREACHABLE_RGB, np.float32)])
        rgb = pal[cls]
        return Coloring(rgb, None, None, None, "tangent class",
                        [(n, CLASS_COLOURS[i]) for i, n in enumerate(CLASS_LABELS)])
    if mode == "phone":
        lut = phone_palette(state)
        names = list(lut)
        P = len(names)
        pal = np.vstack([np.asarray(list(lut.values()), np.float32).reshape(-1, 3),
                         np.asarray(UNREACHABLE_RGB, np.float32)])
        frames_per_code = state.derived("phone_frames", lambda: np.bincount(state.phone_codes, minlength=P + 1))
        counts = state.derived("phone_counts", lambda: _phone_counts(state))
        if state.phone_filter:
            chosen = [n for n in names if n in state.phone_filter]
            cols = np.array([names.index(n) for n in chosen], dtype=np.int64)
            sub = counts[:, cols]
            # a point with any frame of a chosen phone shows the most frequent of them: the filter never hides one
            has = np.diff(sub.indptr) > 0
            rgb = np.broadcast_to(np.asarray(OUTSIDE_RGB, np.float32), (G, 3)).copy()
            rgb[has] = pal[cols[_row_argmax(sub)[has]]]
        else:
            chosen, cols = names, np.arange(P)
            rgb = pal[state.derived("phone_points", lambda: _row_argmax(counts))]
        legend = [(n, tuple(lut[n])) for n in chosen[:LEGEND_MAX]]
        if len(chosen) > LEGEND_MAX:
            legend.append((f"… {len(chosen) - LEGEND_MAX} more (filter phones)", UNREACHABLE_RGB))
        shown = f"{len(chosen)} of {len(names)} phones" if state.phone_filter else f"all {len(names)} phones"
        N = int(frames_per_code.sum())
        share = 100 * float(frames_per_code[cols].sum()) / N if N else 0.0
        return Coloring(rgb, None, None, None, "phone", legend, readout=f"{shown}: {share:.1f}% of frames")
    if mode == "utterance":
        c = manifold.corpus_
        U = len(c.utterances)
        utt = state.derived("utterance_points", lambda: cd.plurality(c.utterance_index, U))
        rgb = categorical_palette(U)[utt] if G else np.zeros((0, 3), np.float32)
        if state.utterance is not None:
            u = c.utterance(state.utterance)
            rgb = rgb * 0.25 + 0.75 * np.asarray(UNREACHABLE_RGB, np.float32)
            rgb[cd.groups_of(np.arange(u.start, u.stop))] = (0.0, 0.0, 0.0)  # every point holding one of its frames
        return Coloring(rgb.astype(np.float32), None, None, None, "utterance")
    raise ValueError(f"colour mode must be one of {modes}, got {mode!r}")
