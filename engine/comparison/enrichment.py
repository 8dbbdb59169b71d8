"""Per state: where on the manifold one level's frames are over- or under-represented against the other's.

A level's *occupancy* of state k is the share of its frames that fall in k. The enrichment
of k is ``log2`` of level b's occupancy over level a's (+1: level b spends twice the share
of its time there; -1: half), with half a frame added to every count so that a state one
level never visits has a finite value. Its significance comes, like every other test of a
comparison, from permuting the labels of whole utterances (or speakers), never of frames.

These are the numbers behind the difference view: :func:`frame_enrichment` spreads them
over the frames.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from engine.comparison.statistics import Family

__all__ = ["state_counts", "enrichment_family", "frame_enrichment", "PSEUDOCOUNT"]

#: frames added to every count of the occupancy ratio
PSEUDOCOUNT = 0.5


def state_counts(labels, utterance_index, n_utterances: int, n_states: int) -> sp.csr_matrix:
    """Frames of each utterance in each state, csr (n_utterances, n_states) float64."""
    labels = np.asarray(labels, np.int64)
    uidx = np.asarray(utterance_index, np.int64)
    data = np.ones(len(labels))
    return sp.csr_matrix((data, (uidx, labels)), shape=(int(n_utterances), int(n_states)))


def enrichment_family(counts: sp.csr_matrix, utterances) -> Family:
    """The family of the states: estimates ``[log2 ratio (K), share_a % (K), share_b % (K)]`` per draw."""
    S = counts[np.asarray(utterances, np.int64)]
    K = counts.shape[1]

    def statistic(sa, sb):
        na, nb = sa.sum(axis=1, keepdims=True), sb.sum(axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            ra = (sa + PSEUDOCOUNT) / (na + PSEUDOCOUNT * K)
            rb = (sb + PSEUDOCOUNT) / (nb + PSEUDOCOUNT * K)
            lr = np.where((na > 0) & (nb > 0), np.log2(rb / ra), np.nan)
            share_a, share_b = 100.0 * sa / na, 100.0 * sb / nb
        zeros = np.zeros_like(lr)
        return np.hstack([lr, share_a, share_b]), np.hstack([np.abs(lr), zeros, zeros])

    return Family("states", S, statistic)


def frame_enrichment(log2_ratio, q, labels, *, alpha: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """Per frame: its state's enrichment and whether it is significant (q < alpha), both (N,)."""
    labels = np.asarray(labels, np.int64)
    lr = np.asarray(log2_ratio, np.float64)
    sig = np.asarray(q, np.float64) < alpha
    return lr[labels], sig[labels]
