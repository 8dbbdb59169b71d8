"""What the comparison views draw, free of Qt, VTK and matplotlib.

A comparison (:class:`engine.comparison.compare.ConditionComparison`) is shown three ways:

* **colour by a field**: each frame takes its utterance's level colour from the session
  palette (:func:`field_colours`; kind ``"field:NAME"``, frames of an unknown level grey);
* **small multiples**: one view per level, each drawing that level's frames
  (:func:`level_frames`) with the cameras, selection and horizon linked by the window;
* **the difference view**: every frame coloured by its state's enrichment on a diverging,
  colour-blind-safe scale (ColorBrewer's PuOr: orange = more of level a, purple = more of
  level b), states whose q-value does not pass faded towards grey (:func:`difference_colours`).

A row of the comparison's table selects what it describes (:func:`row_selection`): a cluster
its phone or landmark, a state that state, a tangent-class measure that class.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PUOR", "NEUTRAL_RGB", "UNKNOWN_LEVEL_RGB", "DifferenceColouring", "diverging_rgb",
           "difference_colours", "level_frames", "field_colours", "RowSelection", "row_selection"]

#: ColorBrewer PuOr (11 classes), orange (negative: more of level a) to purple (positive: more of level b);
#: readable with every common colour-vision deficiency
PUOR = ("#7F3B08", "#B35806", "#E08214", "#FDB863", "#FEE0B6", "#F7F7F7", "#D8DAEB", "#B2ABD2", "#8073AC",
        "#542788", "#2D004B")
#: what a state whose difference is not significant is faded towards
NEUTRAL_RGB = (0.86, 0.86, 0.86)
#: frames of an utterance whose level is unknown
UNKNOWN_LEVEL_RGB = (0.69, 0.69, 0.69)
#: how far a non-significant state's colour is faded towards :data:`NEUTRAL_RGB`
FADE = 0.65


def _table() -> np.ndarray:
    return np.asarray([[int(h[i:i + 2], 16) / 255.0 for i in (1, 3, 5)] for h in PUOR])


def diverging_rgb(values, limit: float) -> np.ndarray:
    """Colours (n, 3) float32 of ``values`` on :data:`PUOR` from ``-limit`` to ``+limit`` (NaN: neutral)."""
    v = np.asarray(values, np.float64)
    if not (np.isfinite(limit) and limit > 0):
        raise ValueError(f"limit={limit!r}: must be a positive number")
    t = np.clip((v / limit + 1.0) / 2.0, 0.0, 1.0) * (len(PUOR) - 1)
    t = np.where(np.isfinite(t), t, (len(PUOR) - 1) / 2.0)
    lo = np.floor(t).astype(int)
    hi = np.minimum(lo + 1, len(PUOR) - 1)
    f = (t - lo)[:, None]
    tab = _table()
    return ((1 - f) * tab[lo] + f * tab[hi]).astype(np.float32)


@dataclass
class DifferenceColouring:
    """The difference view's colours.

    Attributes
    ----------
    rgb : ndarray of shape (N, 3), float32
    values : ndarray of shape (N,)
        Each frame's state's log2 occupancy ratio (level b over a).
    significant : ndarray of shape (N,), bool
        The frame's state passes ``q < alpha``.
    tested : bool
        Some state has a q-value (an untestable design has none: nothing is faded then).
    limit : float
        The colour scale runs from ``-limit`` to ``+limit``.
    title : str
    tick_labels : (str, str)
        What the two ends mean (``more a``, ``more b``).
    """

    rgb: np.ndarray
    values: np.ndarray
    significant: np.ndarray
    tested: bool
    limit: float
    title: str
    tick_labels: tuple


def difference_colours(log2_ratio, q, labels, *, level_a: str = "a", level_b: str = "b", alpha: float = 0.05,
                       limit=None) -> DifferenceColouring:
    """Per frame, its state's enrichment on the diverging scale; states with ``q >= alpha`` faded (a NaN q,
    not tested, is not faded: an untestable design's differences are shown as they are, described).

    Parameters
    ----------
    log2_ratio, q : ndarray of shape (K,)
        Per state (``ConditionComparison.enrichment_[i]``, ``enrichment_q_[i]``; NaN q = not tested).
    labels : ndarray of shape (N,)
        The state of each frame.
    limit : float or None
        Half-range of the scale; None: the largest ``|log2 ratio|`` of a significant state, or of any
        state when none is, at least 0.5 and at most 5.
    """
    lr = np.asarray(log2_ratio, np.float64)
    q = np.asarray(q, np.float64)
    sig_state = q < alpha
    faded_state = np.isfinite(q) & ~sig_state
    labels = np.asarray(labels, np.int64)
    if limit is None:
        pool = np.abs(lr[sig_state & np.isfinite(lr)]) if sig_state.any() else np.abs(lr[np.isfinite(lr)])
        limit = float(np.clip(pool.max() if pool.size else 1.0, 0.5, 5.0))
    values, sig, faded = lr[labels], sig_state[labels], faded_state[labels]
    rgb = diverging_rgb(values, limit)
    rgb[faded] = (1 - FADE) * rgb[faded] + FADE * np.asarray(NEUTRAL_RGB, np.float32)
    tested = bool(np.isfinite(q).any())
    title = f"log2 occupancy ratio ({level_b} / {level_a})" + (f"; faded: q >= {alpha:g}" if tested else
                                                               "; not tested")
    return DifferenceColouring(rgb, values, sig, tested, float(limit), title, (f"more {level_a}", f"more {level_b}"))


def level_frames(values, utterance_index, level) -> np.ndarray:
    """Frame indices (int64) of the utterances whose field value is ``level`` (a small multiple's frames)."""
    per_utt = np.asarray(values, dtype=str) == str(level)
    return np.flatnonzero(per_utt[np.asarray(utterance_index, np.int64)]).astype(np.int64)


def field_colours(values, utterance_index, palette, field: str) -> np.ndarray:
    """Per frame (N, 3) float32: its utterance's level colour of ``field`` (kind ``field:NAME``); unknown grey."""
    values = np.asarray(values, dtype=str)
    levels = sorted(set(values.tolist()) - {""})
    table = np.asarray([palette.colour(f"field:{field}", lv) for lv in levels] + [UNKNOWN_LEVEL_RGB], np.float32)
    code = np.full(len(values), len(levels), np.int64)
    for k, lv in enumerate(levels):
        code[values == lv] = k
    return table[code[np.asarray(utterance_index, np.int64)]]


@dataclass(frozen=True)
class RowSelection:
    """What one row of the comparison table points at in the views.

    Attributes
    ----------
    kind : {"cluster", "state", "class", "dynamics"}
    phones : frozenset of str
        The cluster's phone or landmark (empty unless ``kind == "cluster"``).
    state : int or None
    tangent_class : int or None
        0..3 for a time-in-class row.
    levels : (str, str)
        The two levels compared (level a, level b): the small multiples to show.
    """

    kind: str
    phones: frozenset
    state: int | None
    tangent_class: int | None
    levels: tuple


def row_selection(row) -> RowSelection:
    """The selection a table row stands for (a row of ``ConditionComparison.rows_``)."""
    levels = (str(row["level_a"]), str(row["level_b"]))
    family, target = row["family"], str(row["target"])
    if family == "cluster":
        return RowSelection("cluster", frozenset({target}), None, None, levels)
    if family == "state":
        return RowSelection("state", frozenset(), int(target), None, levels)
    from engine.manifold.tangent import CLASS_NAMES as classes  # (scikit-learn: not before the window is up)

    if family == "dynamics" and target in classes:
        return RowSelection("class", frozenset(), None, classes.index(target), levels)
    if family == "dynamics":
        return RowSelection("dynamics", frozenset(), None, None, levels)
    raise ValueError(f"row family {family!r}: expected 'cluster', 'dynamics' or 'state'")
