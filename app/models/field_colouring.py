"""The manifold's points by per-utterance metadata, and by a comparison's enrichment (Qt-free).

* **colour by a field** (colour mode ``"field"``): every frame takes its utterance's level of
  :attr:`AppState.color_field` (speaker, sex, emotion, text, session, group ...) in the session
  palette's colour of kind ``"field:NAME"``; a drawn point standing for several frames takes
  the level most of them have; an utterance without a value is grey;
* **filter by fields** (:attr:`AppState.field_filter`, any colour mode): frames whose
  utterance is not among the chosen levels are dimmed, as the phone filter dims;
* **the difference view** (colour mode ``"difference"``): every frame takes its state's log2
  occupancy ratio of the comparison shown (:attr:`AppState.comparison`), on the diverging
  scale of :func:`app.models.comparison.difference_colours`; the legend names which level
  each end means.

Fields are read once per manifold through :func:`engine.comparison.fields.utterance_fields`
(the one place per-utterance metadata are read).
"""
from __future__ import annotations

import numpy as np

from app.models.colour_maps import OUTSIDE_RGB, UNREACHABLE_RGB, Coloring, limited_legend

__all__ = ["utterance_field_values", "colour_fields", "field_levels", "frame_mask", "field_coloring",
           "filtered", "difference_coloring", "NO_VALUE"]

#: how the legend names utterances without a value of the field
NO_VALUE = "(no value)"


def utterance_field_values(state) -> dict:
    """``{field: ndarray of str (n_utterances,)}`` of the state's corpus (always ``speaker``), read once."""
    from engine.comparison.fields import utterance_fields

    m = state._require()
    return state.derived("utterance_fields", lambda: utterance_fields(m.corpus_))


def colour_fields(state) -> list[str]:
    """The fields the colour menu offers: every field with a value, ``speaker`` left out (its own mode)."""
    return [k for k, v in utterance_field_values(state).items() if k != "speaker" and np.any(v != "")]


def field_levels(state, name: str) -> list[str]:
    """The levels of field ``name`` in the session palette's order (most utterances first)."""
    values = utterance_field_values(state)[name]
    have = set(values.tolist()) - {""}
    kind = f"field:{name}"
    ranked = [lv for lv in state.palette.levels(kind) if lv in have] if state.palette is not None else []
    return ranked + sorted(have - set(ranked))


def frame_mask(state) -> np.ndarray | None:
    """(N,) bool: the frames the field filter shows (None: no filter)."""
    if not state.field_filter:
        return None

    def compute():
        fields = utterance_field_values(state)
        keep = np.ones(len(state.manifold.corpus_.utterances), bool)
        for name in sorted({f for f, _ in state.field_filter}):
            keep &= np.isin(fields[name], sorted(lv for f, lv in state.field_filter if f == name))
        return keep[state.manifold.corpus_.utterance_index]

    return state.derived(("field_mask", state.field_filter), compute)


def _grey(state, title: str, readout: str) -> Coloring:
    G = state.cloud.n_points
    return Coloring(np.broadcast_to(np.asarray(UNREACHABLE_RGB, np.float32), (G, 3)).copy(), None, None, None, title,
                    readout=readout)


def field_coloring(state) -> Coloring:
    """Colours of the drawn points by their utterances' level of :attr:`AppState.color_field`."""
    name = state.color_field
    if name is None:
        return _grey(state, "field", "choose a field to colour by (Colour: Field …)")
    values = utterance_field_values(state)[name]
    levels = field_levels(state, name)
    code_of = {lv: k for k, lv in enumerate(levels)}
    code = np.asarray([code_of.get(v, len(levels)) for v in values.tolist()], np.int64)
    cd, c = state.cloud, state.manifold.corpus_
    top = state.derived(("field_points", name), lambda: cd.plurality(code[c.utterance_index], len(levels) + 1))
    pal = np.vstack([state.palette.array(f"field:{name}", levels), np.asarray(UNREACHABLE_RGB, np.float32)])
    legend = [(lv, tuple(float(x) for x in pal[k])) for k, lv in enumerate(levels)]
    legend = limited_legend(legend, f"levels of {name}")
    if np.any(code == len(levels)):
        legend.append((NO_VALUE, UNREACHABLE_RGB))
    return Coloring(pal[top].astype(np.float32), None, None, None, name, legend,
                    readout=f"{name}: {len(levels)} level{'s' * (len(levels) != 1)}")


def filtered(coloring: Coloring, state) -> Coloring:
    """``coloring`` with the points the field filter does not show dimmed (no filter: unchanged)."""
    mask = frame_mask(state)
    if mask is None:
        return coloring
    cd = state.cloud
    shown = state.derived(("field_mask_points", state.field_filter),
                          lambda: cd.plurality(mask.astype(np.int64), 2).astype(bool))
    rgb = coloring.rgb.copy()
    rgb[~shown] = OUTSIDE_RGB
    names = {}
    for f, lv in sorted(state.field_filter):
        names.setdefault(f, []).append(lv)
    text = "; ".join(f"{f} {', '.join(lvs)}" for f, lvs in names.items())
    share = 100.0 * float(mask.mean()) if mask.size else 0.0
    readout = "; ".join(x for x in (coloring.readout, f"shown: {text} ({share:.1f}% of frames)") if x)
    legend = list(coloring.legend) + [("other levels (dimmed)", OUTSIDE_RGB)]
    return Coloring(rgb, coloring.values, coloring.cmap, coloring.clim, coloring.title, legend, coloring.ticks,
                    coloring.tick_labels, readout)


def difference_coloring(state) -> Coloring:
    """The difference view: each drawn point's state's log2 occupancy ratio (level b over a) of the comparison
    shown, significant states in full colour, the others faded (:func:`app.models.comparison.difference_colours`)."""
    from app.models.comparison import NEUTRAL_RGB, PUOR, difference_colours, diverging_rgb

    shown = state.comparison
    if shown is None:
        return _grey(state, "difference", "run a comparison (Compare panel) to colour by where the levels differ")
    r, i = shown.result, shown.contrast
    a, b = shown.levels
    dc = difference_colours(r.enrichment_[i], r.enrichment_q_[i], state.cloud.state, level_a=a, level_b=b,
                            alpha=r.alpha)
    ends = {lv: tuple(float(x) for x in diverging_rgb([v], 1.0)[0]) for lv, v in ((a, -0.8), (b, 0.8))}
    legend = [(f"more {a} (orange)", ends[a]), (f"more {b} (purple)", ends[b])]
    q = np.asarray(r.enrichment_q_[i], float)
    if dc.tested:
        n_sig = int(np.sum(q < r.alpha))
        legend.append((f"q >= {r.alpha:g} (faded)", NEUTRAL_RGB))
        readout = f"{b} against {a}: {n_sig} of {len(q)} states differ at q < {r.alpha:g}"
    else:
        readout = f"{b} against {a}: descriptive only (the design cannot be tested)"
    table = diverging_rgb(np.linspace(-1.0, 1.0, 2 * len(PUOR) + 1), 1.0)
    return Coloring(dc.rgb, dc.values.astype(np.float32), table, (-dc.limit, dc.limit),
                    f"log2 occupancy\n{b} / {a}", legend, readout=readout)
