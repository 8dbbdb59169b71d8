"""Lip aperture and kinematic landmarks: what "opening" means, and key frames without phones.

When a corpus names its upper- and lower-lip points (``Corpus.point_roles``), the
**lip aperture** is the distance between their centroids per frame. It defines
"opening" for the tangent frames and the movement classes (instead of whatever the
first shape component happens to be), and :mod:`engine.manifold.class_agreement` checks a
fitted manifold against it; :func:`aperture_definition` says in words which points
define it.

**Kinematic landmarks** are the frames where, within an utterance, the aperture
reaches a maximum (``open``) or a minimum (``closed``), or its velocity peaks while
opening (``opening``) or closing (``closing``). They stand in for phone mid-points in
corpora without phone labels: :func:`with_kinematic_labels` writes them as labelled
intervals centred on each landmark, so targets, clusters, synthesis and evaluation
work unchanged on them (see docs/DECISIONS.md, D6).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["lip_aperture", "aperture_definition", "aperture_velocity", "kinematic_landmarks",
           "with_kinematic_labels", "with_landmark_labels", "kinematic_key_frames", "kinematic_if_unlabelled",
           "has_kinematic_labels", "LANDMARK_LABELS"]

#: landmark label per kind
LANDMARK_LABELS = ("open", "closed", "opening", "closing")


def lip_aperture(corpus, *, executor=None) -> np.ndarray | None:
    """Distance between the upper- and lower-lip point centroids per frame.

    Parameters
    ----------
    corpus : Corpus
    executor : engine.scale.executor.DaskExecutor or None
        With frames stored in blocks, one task per block file computes its frames'
        aperture; otherwise a loop over windows of frames here (same values).

    Returns
    -------
    ndarray of shape (n_frames,) float64, or None when the corpus names no upper and
    lower lip points.
    """
    up, lo = corpus.role_points("upper_lip"), corpus.role_points("lower_lip")
    if up.size == 0 or lo.size == 0:
        return None
    from functools import partial

    from engine.recordings.frame_blocks import map_frames

    parts = map_frames(partial(_aperture_rows, up=up, lo=lo, dims=corpus.dims), corpus.frames, executor=executor)
    return np.concatenate(parts)


def aperture_definition(corpus) -> str:
    """What defines "opening" in ``corpus``, in words: the lip aperture and its points, or the stand-in."""
    up, lo = corpus.role_points("upper_lip"), corpus.role_points("lower_lip")
    if up.size == 0 or lo.size == 0:
        return ("the first shape component F^x_1, standing in for the lip aperture (arbitrary units): the corpus "
                "names no upper_lip / lower_lip points (import with --layout or --roles to name them)")
    names = corpus.point_names or [str(i) for i in range(corpus.n_points)]

    def which(idx):
        shown = ", ".join(str(names[i]) for i in idx[:4])
        return shown + (f" and {idx.size - 4} more" if idx.size > 4 else "")

    what = "centroids" if up.size > 1 or lo.size > 1 else "points"
    return (f"lip aperture: the distance between the upper_lip {what} ({which(up)}) and the lower_lip "
            f"{what} ({which(lo)}), in mm")


def _aperture_rows(F, a, b, *, up, lo, dims):
    """Lip aperture of the frames ``F`` (n, C) (rows ``[a, b)`` of the corpus), float64 (n,)."""
    from engine.recordings.corpus import frame_points

    P = frame_points(F, dims).astype(np.float64)  # (n, V, 3)
    return np.linalg.norm(P[:, up].mean(axis=1) - P[:, lo].mean(axis=1), axis=1)


def aperture_velocity(aperture, bounds) -> np.ndarray:
    """Forward difference of the aperture per frame, inside utterances (frames/s not applied).

    The first frame of each utterance uses a[1] - a[0] like :func:`engine.recordings.bounds.velocities`.
    """
    from engine.recordings.bounds import velocities

    return velocities(np.asarray(aperture, np.float64)[:, None], bounds)[:, 0]


def _smooth(x, width):
    if width <= 1 or len(x) < width:
        return x
    k = np.ones(width) / width
    pad = width // 2
    xp = np.pad(x, (pad, width - 1 - pad), mode="edge")
    return np.convolve(xp, k, mode="valid")


def kinematic_landmarks(corpus, *, aperture=None, prominence=0.15, min_separation_s=0.06, smooth_s=0.03):
    """Aperture maxima / minima and opening / closing velocity peaks, per utterance.

    Parameters
    ----------
    corpus : Corpus
    aperture : ndarray of shape (n_frames,), optional
        Default :func:`lip_aperture`; without upper/lower lip roles, the first shape
        principal component of the frames stands in (reported by the caller).
    prominence : float, default=0.15
        A peak must stand out by this fraction of the aperture's (velocity's) robust
        range (5th-95th percentile) over the corpus.
    min_separation_s : float, default=0.06
        Least time between two landmarks of the same kind.
    smooth_s : float, default=0.03
        Moving-average window applied before peak picking.

    Returns
    -------
    frames : int ndarray of shape (n,)
        Corpus frame indices, sorted; at most one landmark per frame.
    labels : str ndarray of shape (n,)
        One of :data:`LANDMARK_LABELS`.
    """
    from scipy.signal import find_peaks

    if not 0 < float(prominence) < 1:
        raise ValueError(f"prominence must be in (0, 1), got {prominence}")
    a = lip_aperture(corpus) if aperture is None else np.asarray(aperture, np.float64)
    if a is None:
        raise ValueError(f"{corpus.name}: no upper_lip / lower_lip points to measure the aperture; import with a "
                         "layout naming them (lipspace import --layout), or pass aperture=")
    rate = corpus.rate
    w = max(1, int(round(smooth_s * rate)))
    dist = max(1, int(round(min_separation_s * rate)))
    lo_a, hi_a = np.percentile(a, [5, 95])
    v_all = aperture_velocity(a, corpus.bounds)
    lo_v, hi_v = np.percentile(np.abs(v_all), [5, 95])
    frames, labels = [], []
    for u in corpus.utterances:
        seg = _smooth(a[u.start:u.stop], w)
        if len(seg) < 3:
            continue
        vel = np.gradient(seg)
        found = {}
        for sig, lab, prom in ((seg, "open", hi_a - lo_a), (-seg, "closed", hi_a - lo_a),
                               (vel, "opening", hi_v - lo_v), (-vel, "closing", hi_v - lo_v)):
            kw = {"prominence": prominence * prom} if prom > 0 else {}
            if lab in ("opening", "closing"):
                kw["height"] = prominence * hi_v
            pk, _ = find_peaks(sig, distance=dist, **kw)
            for p in pk:
                found.setdefault(int(p), lab)  # extrema win over velocity peaks at the same frame
        for p in sorted(found):
            frames.append(u.start + p)
            labels.append(found[p])
    return np.array(frames, dtype=np.int64), np.array(labels, dtype=str)


def with_kinematic_labels(corpus, **landmark_params):
    """The corpus with its phones replaced by kinematic landmark intervals.

    Each landmark becomes an interval labelled with its kind (:data:`LANDMARK_LABELS`)
    centred on its frame, half-way to its neighbours at most (so its mid-point is the
    landmark), so anything that uses phone mid-points (targets, clusters, evaluation)
    uses the landmarks. ``history`` records it.

    Returns
    -------
    Corpus
    """
    frames, labels = kinematic_landmarks(corpus, **landmark_params)
    return with_landmark_labels(corpus, frames, labels, note=f"{_LANDMARK_NOTE} {len(frames)} kinematic landmarks "
                                                             f"({', '.join(LANDMARK_LABELS)})")


def with_landmark_labels(corpus, frames, labels, *, note: str):
    """The corpus with its phones replaced by intervals labelled ``labels`` centred on corpus ``frames``.

    Each interval reaches half-way to its neighbours at most (and 0.1 s), so its mid-point
    is its frame; ``note`` is appended to the history. Used for kinematic and gestural
    landmarks (:mod:`engine.recordings.signals.gestures`).
    """
    frames = np.asarray(frames, np.int64)
    labels = np.asarray(labels, dtype=str)
    order = np.argsort(frames, kind="stable")
    frames, labels = frames[order], labels[order]
    rate = corpus.rate
    utts = []
    for u in corpus.utterances:
        sel = (frames >= u.start) & (frames < u.stop)
        f = frames[sel] - u.start
        lab = labels[sel]
        ph = []
        dur = u.n_frames / rate
        for i, (fi, li) in enumerate(zip(f, lab)):
            t = fi / rate
            gaps = [0.1, dur - t, t]
            if i:
                gaps.append((t - f[i - 1] / rate) / 2)
            if i + 1 < len(f):
                gaps.append((f[i + 1] / rate - t) / 2)
            h = min(gaps)
            s, e = (t - h, t + h) if h > 0 else (0.0, 0.5 / rate)
            ph.append((s, e, str(li)))
        utts.append(replace(u, phones=tuple(ph)))
    return replace(corpus, utterances=utts, history=list(corpus.history) + [note])


#: how :func:`with_kinematic_labels` starts its history line
_LANDMARK_NOTE = "phones replaced by"


def has_kinematic_labels(corpus) -> bool:
    """True when the corpus's labels are kinematic landmarks (:func:`with_kinematic_labels`), not phones."""
    return any(h.startswith(_LANDMARK_NOTE) and "kinematic landmarks" in h for h in corpus.history)


def kinematic_key_frames(corpus, utterance, **landmark_params) -> np.ndarray:
    """Kinematic landmark frames of one utterance, 0-based within it (target frames for evaluation).

    Parameters
    ----------
    corpus : Corpus
    utterance : str or Utterance

    Returns
    -------
    int ndarray of shape (n,), strictly increasing.
    """
    u = corpus.utterance(getattr(utterance, "id", utterance))
    frames, _ = kinematic_landmarks(corpus.subset([u.id]), **landmark_params)
    return frames


def kinematic_if_unlabelled(corpus):
    """``(corpus, note)``: the corpus with kinematic landmark labels when it has no phone labels at all.

    ``note`` is a sentence saying so (None when the corpus has phones and is returned
    unchanged). Without upper/lower lip roles the first shape principal component of
    the frames stands in for the aperture, and the note says that too.
    """
    if any(u.phones for u in corpus.utterances):
        return corpus, None
    ap = lip_aperture(corpus)
    proxy = ""
    if ap is None:
        F = corpus.frames.astype(np.float64)
        F = F - F.mean(axis=0)
        _, _, Vt = np.linalg.svd(F[:: max(1, len(F) // 5000)], full_matrices=False)
        ap = F @ Vt[0]
        proxy = " (no upper/lower lip roles: the first shape component stands in for the aperture)"
    out = with_kinematic_labels(corpus, aperture=ap)
    n = sum(len(u.phones) for u in out.utterances)
    return out, (f"{corpus.name} has no phone labels: using {n} kinematic landmarks (aperture maxima 'open', "
                 f"minima 'closed', peak velocities 'opening' / 'closing') as labels{proxy}")
