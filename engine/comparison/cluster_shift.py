"""Per phone or landmark cluster: how far its centre moves between two levels, and how its spread changes.

The members of a cluster are its mid-point frames (:class:`engine.manifold.clusters.PhoneClusters`,
fitted on both levels together). For each level the centre is the mean of its members, in
Y (the first ``n_dims`` dimensions of F^y: shape with its dynamics) and in X (the first
``n_dims`` shape components of F^x: shape only), and the spread is the RMS distance of the
members from it. Per cluster and space the family reports:

``centre shift``
    The distance between the two levels' centres. In Y, whose coordinates have no unit,
    it is divided by the pooled within-level standard deviation per dimension (a distance
    in s.d.s, like Cohen's d); in X it is the displacement of the mean lip shape in the
    corpus's unit, as an RMS over the points (mm per point).
``spread ratio``
    Level b's spread over level a's (> 1: level b varies more).

A distance is never negative, so with no true shift it still comes out above zero from
sampling noise alone: the p-value, not the interval, says whether a shift is there.
"""
from __future__ import annotations

import numpy as np

from engine.comparison.statistics import Family

__all__ = ["member_utterances", "cluster_family", "SPACES"]

#: the two spaces a cluster is compared in
SPACES = ("Y", "X")


def member_utterances(clusters, utterance_index) -> tuple[np.ndarray, np.ndarray]:
    """``(cluster of each member, utterance of each member)``, both (M,) int64."""
    offsets = np.asarray(clusters.member_offsets_)
    which = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    return which.astype(np.int64), np.asarray(utterance_index)[clusters.members_].astype(np.int64)


def cluster_family(clusters, coords, utterance_index, utterances, *, space: str, n_dims: int,
                   scale: float = 1.0) -> Family:
    """The family of one space: estimates ``[shift (C), spread ratio (C), n_a (C), n_b (C)]`` per draw.

    Parameters
    ----------
    clusters : PhoneClusters, fitted
    coords : ndarray of shape (N, >= n_dims)
        F^y or F^x of every frame.
    utterance_index : ndarray of shape (N,)
        Utterance of every frame.
    utterances : ndarray of shape (U,)
        The design's utterances.
    space : {"Y", "X"}
        Y shifts are standardised by the pooled s.d.; X shifts are multiplied by ``scale``.
    n_dims : int
    scale : float
        X: 1 / sqrt(points), which makes the norm of a frame difference an RMS per point.
    """
    if space not in SPACES:
        raise ValueError(f"space={space!r}; expected one of {SPACES}")
    C = len(clusters.phones_)
    d = int(min(n_dims, coords.shape[1]))
    which, utt = member_utterances(clusters, utterance_index)
    utterances = np.asarray(utterances, np.int64)
    size = max(int(np.max(utterance_index, initial=-1)), int(np.max(utterances, initial=-1))) + 1
    row = np.full(size, -1, np.int64)
    row[utterances] = np.arange(len(utterances))
    r = row[utt]
    keep = r >= 0
    X = np.asarray(coords[clusters.members_[keep], :d], np.float64)
    U = len(utterances)
    S = np.zeros((U, C, d + 2))
    np.add.at(S, (r[keep], which[keep], 0), 1.0)
    for j in range(d):
        np.add.at(S, (r[keep], which[keep], 1 + j), X[:, j])
    np.add.at(S, (r[keep], which[keep], 1 + d), (X ** 2).sum(axis=1))
    standardise = space == "Y"

    def statistic(sa, sb):
        n = sa.shape[0]
        A, B = sa.reshape(n, C, d + 2), sb.reshape(n, C, d + 2)
        na, nb = A[..., 0], B[..., 0]
        with np.errstate(invalid="ignore", divide="ignore"):
            ma, mb = A[..., 1:1 + d] / na[..., None], B[..., 1:1 + d] / nb[..., None]
            va = np.maximum(A[..., 1 + d] - na * (ma ** 2).sum(-1), 0.0) / (na - 1)
            vb = np.maximum(B[..., 1 + d] - nb * (mb ** 2).sum(-1), 0.0) / (nb - 1)
            shift = np.linalg.norm(mb - ma, axis=-1)
            if standardise:
                pooled = ((na - 1) * va + (nb - 1) * vb) / (na + nb - 2) / d
                shift = shift / np.sqrt(pooled)
            else:
                shift = shift * scale
            ratio = np.sqrt(vb / va)
            ok = (na >= 2) & (nb >= 2)
            shift = np.where(ok, shift, np.nan)
            ratio = np.where(ok & (va > 0) & (vb > 0), ratio, np.nan)
            log_ratio = np.abs(np.log(ratio))
        zeros = np.zeros_like(na)
        return np.hstack([shift, ratio, na, nb]), np.hstack([shift, log_ratio, zeros, zeros])

    return Family(f"clusters {space}", S.reshape(U, C * (d + 2)), statistic)
