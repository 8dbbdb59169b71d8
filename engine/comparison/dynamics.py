"""The dynamics on the manifold per utterance, and the family comparing them between two levels.

Every measure is a ratio of two per-utterance sums (numerator, denominator), so a level's
value is its utterances' numerators summed over their denominators summed (a frame-weighted
mean), and a comparison is the ratio of the two levels' values:

``opening speed``
    Mean absolute opening velocity read on the manifold (the tangent frames' ``velocity_``:
    the lip aperture's rate of change, mm/s, when the corpus names its lips), over frames with
    a step; also over opening frames only (``while opening``) and closing frames only
    (``while closing``).
``time in class``
    Share of the frames with a step that fall in each of the four tangent classes (%).
``future hemisphere``
    Mean, over the level's frames, of the share of the corpus's frames whose state can follow
    the frame's state within the horizon (%): how open the future is where the level moves.
    The states and their graph are the manifold's, shared by both levels.
``path length per second``
    Length of the trajectory in F^y (all embedding dimensions, consecutive frames of an
    utterance) per second of speech.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine.comparison.statistics import Family
from engine.graph.hemispheres import horizon_hops
from engine.manifold.tangent import CLASS_NAMES
from engine.progress import report

__all__ = ["UtteranceDynamics", "utterance_dynamics", "dynamics_family", "hemisphere_sizes"]


@dataclass
class UtteranceDynamics:
    """Per-utterance sums of each dynamics measure.

    Attributes
    ----------
    measures, targets, units : list of str, length M
        What each column is (``measure``, its ``target`` e.g. a class name, and the unit of a level's value).
    numerator, denominator : ndarray of shape (n_utterances, M), float64
    scale : ndarray of shape (M,)
        Factor from numerator / denominator to the unit (100 for percentages).
    horizon_s : float
    """

    measures: list
    targets: list
    units: list
    numerator: np.ndarray
    denominator: np.ndarray
    scale: np.ndarray
    horizon_s: float


def hemisphere_sizes(graph, labels, horizon_s: float, rate: float, *, progress=None) -> np.ndarray:
    """Per state, the share of frames whose state lies within the horizon in its future hemisphere, (K,)."""
    K = graph.centroids_.shape[0]
    h = horizon_hops(horizon_s, rate)
    counts = np.bincount(np.asarray(labels), minlength=K).astype(np.float64)
    total = counts.sum()
    out = np.empty(K)
    for k in range(K):
        if k % 64 == 0:
            report(progress, "hemispheres", k, K)
        out[k] = counts[graph.future(k) <= h].sum() / total
    report(progress, "hemispheres", K, K)
    return out


def utterance_dynamics(manifold, *, horizon_s: float = 0.1, unit_index=None, progress=None) -> UtteranceDynamics:
    """The per-utterance sums of every dynamics measure of a fitted manifold (module docstring).

    Parameters
    ----------
    manifold : engine.manifold.model.Manifold, fitted
    horizon_s : float
        Horizon of the future hemisphere (seconds; 0.1 = the window's default).
    unit_index : ndarray of shape (N,) or None
        The unit whose sums each frame adds to (default: its utterance). ``np.arange(N)`` gives
        every frame its own row: what a test treating frames as independent would resample.
    progress : callable(stage, done, total) or None

    Returns
    -------
    UtteranceDynamics
    """
    if not (np.isfinite(horizon_s) and horizon_s > 0):
        raise ValueError(f"horizon_s={horizon_s!r}: must be a positive number of seconds (e.g. 0.1)")
    c = manifold.corpus_
    tangent, states = manifold.tangent_, manifold.states_
    uidx = c.utterance_index
    owner = uidx if unit_index is None else np.asarray(unit_index, np.int64)
    n_owners = len(c.utterances) if unit_index is None else int(owner.max(initial=-1)) + 1

    def per_utt(x):
        return np.bincount(owner, weights=np.asarray(x, np.float64), minlength=n_owners)

    cls = np.asarray(tangent.classes_)
    step = cls >= 0
    speed = np.abs(np.asarray(tangent.velocity_, np.float64))
    opening, closing = step & (cls <= 1), step & (cls >= 2)
    unit = str(getattr(tangent, "opening_unit_", "") or c.unit_label)
    vunit = f"{unit}/s"
    meas, tgts, units, num, den, scale = [], [], [], [], [], []

    def add(measure, target, u, n, d, s=1.0):
        meas.append(measure), tgts.append(target), units.append(u), num.append(n), den.append(d), scale.append(s)

    n_step = per_utt(step)
    add("opening speed", "all frames", vunit, per_utt(speed * step), n_step)
    add("opening speed", "while opening", vunit, per_utt(speed * opening), per_utt(opening))
    add("opening speed", "while closing", vunit, per_utt(speed * closing), per_utt(closing))
    for k, name in enumerate(CLASS_NAMES):
        add("time in class", name, "%", per_utt(cls == k), n_step, 100.0)
    hemi = hemisphere_sizes(states, states.labels_, horizon_s, c.rate, progress=progress)
    n_frames = per_utt(np.ones(len(uidx)))
    add("future hemisphere", f"within {horizon_s * 1000:g} ms", "% of frames", per_utt(hemi[states.labels_]),
        n_frames, 100.0)
    Fy = np.asarray(manifold.Fy_)
    d = np.zeros(len(uidx))
    if len(uidx) > 1:
        same = uidx[1:] == uidx[:-1]
        d[1:] = np.where(same, np.linalg.norm(np.diff(Fy, axis=0).astype(np.float64), axis=1), 0.0)
    add("path length per second", "F^y", "Y units/s", per_utt(d), n_frames / c.rate)
    return UtteranceDynamics(meas, tgts, units, np.column_stack(num), np.column_stack(den),
                             np.asarray(scale, np.float64), float(horizon_s))


def dynamics_family(dyn: UtteranceDynamics, utterances) -> Family:
    """The family comparing the levels' values: estimate = value_b / value_a, test = ``|log|`` of it.

    ``utterances``: the design's utterances (indices into the corpus's). The statistic returns
    (n, 3M): ``[ratio, value_a, value_b]`` as estimates (only the ratio is tested).
    """
    utt = np.asarray(utterances, np.int64)
    S = np.hstack([dyn.numerator[utt], dyn.denominator[utt]])
    M = dyn.numerator.shape[1]
    scale = dyn.scale

    def statistic(sa, sb):
        with np.errstate(invalid="ignore", divide="ignore"):
            va = sa[:, :M] / sa[:, M:] * scale
            vb = sb[:, :M] / sb[:, M:] * scale
            ratio = np.where((va > 0) & (vb > 0), vb / va, np.nan)
            test = np.abs(np.log(ratio))
        return np.hstack([ratio, va, vb]), np.hstack([test, np.zeros_like(va), np.zeros_like(vb)])

    return Family("dynamics", S, statistic)
