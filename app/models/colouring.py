"""How the explorer colours the manifold's points, per colour mode, free of Qt and VTK.

* density: :data:`DENSITY_CMAP` (perceptually uniform) of the log k-NN density;
* hop distance (the paper's Fig. 2b) within a time horizon: :mod:`app.models.hop_colouring`;
* tangent class, phone, speaker, utterance: the session palette
  (:class:`app.models.palette.SessionPalette`, ``state.palette``), the one table of category
  colours the view, its legend, the clusters table, the timeline and the figures all read;
  a phone filter colours only the chosen phones and dims the rest.

While ellipsoids are shown the points are dimmed (:func:`dim`) so the clusters stand out.
The continuous maps and fixed colours are :mod:`app.models.colour_maps` (re-exported here).
"""
from __future__ import annotations

import numpy as np

from app.models.colour_maps import (
    DENSITY_CMAP,
    FUTURE_CMAP,
    LEGEND_MAX,
    OUTSIDE_RGB,
    PAST_CMAP,
    RESERVED_COLOURS,
    UNREACHABLE_RGB,
    Coloring,
    colormap_rgb,
    colour_table,
    delta_e,
    dim,
    limited_legend,
    map_values,
)
from app.models.hop_colouring import hemisphere_coloring, hop_table
from app.models.palette import CLASS_LABELS

__all__ = ["Coloring", "CLASS_LABELS", "UNREACHABLE_RGB", "OUTSIDE_RGB", "DENSITY_CMAP", "FUTURE_CMAP", "PAST_CMAP",
           "RESERVED_COLOURS", "point_colors", "hop_table", "hemisphere_coloring", "dim", "delta_e", "LEGEND_MAX",
           "colour_table", "colormap_rgb", "DENSITY_TITLE", "UNKNOWN_SPEAKER"]

#: the colour bar's title in density mode: the value and its unit
DENSITY_TITLE = "log density\n(ln frames/unit³)"
#: how the legend names utterances that name no speaker
UNKNOWN_SPEAKER = "(speaker not named)"


# --------------------------------------------------------------------------- every mode
def point_colors(mode: str, manifold, state=None) -> Coloring:
    """Colours of the points the manifold view draws for colour mode ``mode``: one per frame
    while every frame is drawn, else one per group of frames (``state.cloud``, an
    :class:`app.models.lod.CloudDetail`), computed from all the frames it stands for.

    ``state`` (an :class:`app.models.state.AppState`) supplies the selection and hemisphere
    (distance mode), the horizon, the current utterance (utterance mode highlights it),
    the phone filter (phone mode), the shown ellipsoids (points dimmed), the palette, the
    cloud and the cached density / phones.
    """
    from app.models.state import COLOR_MODES, AppState

    if state is None:
        state = AppState(manifold)
    c = _mode_colors(mode, manifold, state, COLOR_MODES)
    if state.field_filter:
        from app.models.field_colouring import filtered

        c = filtered(c, state)
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


def _categories(state, kind: str, codes_of_frames, names, key: str):
    """(rgb (G, 3), the palette's colours (n, 3), each point's category (G,)) of a per-frame category,
    a point taking the category most of its frames have."""
    cd = state.cloud
    pal = state.palette.array(kind, names)
    top = state.derived(key, lambda: cd.plurality(codes_of_frames(), len(names)))
    return (pal[top] if cd.n_points else np.zeros((0, 3), np.float32)), pal, top


def _mode_colors(mode, manifold, state, modes) -> Coloring:
    cd = state.cloud
    G = cd.n_points
    if mode == "density":
        v = state.density if cd.whole else cd.density  # a group: the histogram density of its cell
        clim = (float(np.percentile(v, 2)), float(np.percentile(v, 98)))
        return Coloring(map_values(v, DENSITY_CMAP, clim), v, DENSITY_CMAP, clim, DENSITY_TITLE)
    if mode == "distance":
        if state.state is None:
            v = np.full(G, np.nan, dtype=np.float32)
            return Coloring(np.broadcast_to(np.asarray(UNREACHABLE_RGB, np.float32), (G, 3)).copy(), v, None,
                            None, "hop distance", readout="click a point to colour its hemisphere")
        if state.hemisphere == "off":
            v = np.where(cd.state == state.state, 0.0, np.nan).astype(np.float32)
            rgb = np.where(np.isfinite(v)[:, None], np.asarray(RESERVED_COLOURS["selected"], np.float32),
                           np.asarray(UNREACHABLE_RGB, np.float32)).astype(np.float32)
            return Coloring(rgb, v, None, None, "selected state",
                            [("the selected state", RESERVED_COLOURS["selected"]), ("other states", UNREACHABLE_RGB)])
        return hemisphere_coloring(manifold, state.state, state.hemisphere, state.horizon_ms, cloud=cd)
    if mode == "class":
        cls = state.derived("class_points", lambda: cd.plurality(
            np.where(np.asarray(manifold.tangent_.classes_) < 0, 4, manifold.tangent_.classes_), 5))
        pal = np.vstack([state.palette.array("class", CLASS_LABELS), np.asarray(UNREACHABLE_RGB, np.float32)])
        legend = [(n, tuple(float(x) for x in pal[i])) for i, n in enumerate(CLASS_LABELS)]
        return Coloring(pal[cls], None, None, None, "tangent class", legend + [("no step", UNREACHABLE_RGB)])
    if mode == "phone":
        return _phone_colors(state)
    if mode == "speaker":
        c = manifold.corpus_
        names = [u.speaker or "" for u in c.utterances]
        levels = list(dict.fromkeys(names))
        code = np.asarray([levels.index(n) for n in names], np.int64)
        rgb, pal, top = _categories(state, "speaker", lambda: code[c.utterance_index], levels, "speaker_points")
        shown = [n or UNKNOWN_SPEAKER for n in levels]
        if "" in levels:  # no name: grey, not a speaker's colour
            rgb[top == levels.index("")] = UNREACHABLE_RGB
            pal[levels.index("")] = UNREACHABLE_RGB
        legend = limited_legend([(n, tuple(float(x) for x in pal[k])) for k, n in enumerate(shown)], "speakers")
        return Coloring(rgb.astype(np.float32), None, None, None, "speaker", legend,
                        readout=f"{len([n for n in levels if n])} named speaker(s)")
    if mode == "utterance":
        c = manifold.corpus_
        ids = [u.id for u in c.utterances]
        rgb, pal, _top = _categories(state, "utterance", lambda: c.utterance_index, ids, "utterance_points")
        legend = [(n, tuple(float(x) for x in pal[k])) for k, n in enumerate(ids)]
        if state.utterance is not None:
            u = c.utterance(state.utterance)
            rgb = rgb * 0.25 + 0.75 * np.asarray(UNREACHABLE_RGB, np.float32)
            rgb[cd.groups_of(np.arange(u.start, u.stop))] = (0.0, 0.0, 0.0)  # every point holding one of its frames
            legend = [(f"{u.id} (current)", (0.0, 0.0, 0.0)), ("the other utterances (faded)", UNREACHABLE_RGB)]
        return Coloring(rgb.astype(np.float32), None, None, None, "utterance", limited_legend(legend, "utterances"))
    if mode in ("field", "difference"):  # per-utterance metadata, and a comparison's enrichment
        from app.models.field_colouring import difference_coloring, field_coloring

        return field_coloring(state) if mode == "field" else difference_coloring(state)
    raise ValueError(f"colour mode must be one of {modes}, got {mode!r}")


def _phone_colors(state) -> Coloring:
    cd = state.cloud
    G = cd.n_points
    names = list(state.phone_names)
    P = len(names)
    pal = np.vstack([state.palette.array("phone", names), np.asarray(UNREACHABLE_RGB, np.float32)])
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
    legend = limited_legend([(n, tuple(float(x) for x in pal[names.index(n)])) for n in chosen], "filter phones")
    if state.phone_filter:
        legend.append(("other phones (dimmed)", OUTSIDE_RGB))
    shown = f"{len(chosen)} of {len(names)} phones" if state.phone_filter else f"all {len(names)} phones"
    N = int(frames_per_code.sum())
    share = 100 * float(frames_per_code[cols].sum()) / N if N else 0.0
    return Coloring(rgb, None, None, None, "phone", legend, readout=f"{shown}: {share:.1f}% of frames")
