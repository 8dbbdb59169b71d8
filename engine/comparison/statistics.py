"""Estimates, permutation p-values and bootstrap intervals of statistics built from per-utterance sums.

A :class:`Family` is a set of statistics that answer one question (the clusters, the
dynamics, the states). It holds a matrix ``S`` (U, D) of per-utterance sufficient
statistics (counts, sums, sums of squares: dense, or a scipy sparse matrix) and a function
``statistic(sum_a, sum_b) -> (estimate, test)`` of the two levels' sums, both (n, D) for n
draws, returning (n, m) arrays: the estimate (what is reported) and the test statistic
(larger = farther from "no difference"). Every draw of :mod:`engine.comparison.resampling`
is then two matrix products, for all statistics of all families at once.

* p-value: the share of permutations whose test statistic is at least the observed one,
  ``(1 + b) / (1 + n)`` for ``n`` random permutations, ``b / n`` for exact enumeration (the
  observed arrangement is one of the ``n``). Draws where a statistic is undefined (a level
  left without members) are left out of its count.
* interval: percentile bootstrap of the estimate (NaN when fewer than half the draws give one).
* q-value: Benjamini-Hochberg over a family (:func:`bh_qvalues`).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from engine.comparison.resampling import bootstrap_draws, is_exact, permutation_draws
from engine.progress import report

__all__ = ["Family", "FamilyResult", "run_families", "bh_qvalues", "level_sums"]

#: relative tolerance under which a permuted test statistic counts as equal to the observed one
_TIES = 1e-9


@dataclass
class Family:
    """Statistics answering one question, from per-utterance sums.

    Attributes
    ----------
    name : str
    S : ndarray or scipy.sparse matrix of shape (U, D)
        Per-utterance sufficient statistics over the design's utterances.
    statistic : callable
        ``statistic(sum_a (n, D), sum_b (n, D)) -> (estimate (n, m), test (n, m))``.
    """

    name: str
    S: object
    statistic: Callable


@dataclass
class FamilyResult:
    """Per statistic of a family: ``estimate``, ``ci_low``, ``ci_high``, ``p`` (m,) float64, and how p was had."""

    name: str
    estimate: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    p: np.ndarray
    n_permutations: int
    exact: bool


def level_sums(S, w_a: np.ndarray, w_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(w_a @ S, w_b @ S)`` as dense (n, D) arrays, S dense or sparse (``run_families`` transposes a sparse S
    once, not per batch)."""
    if isinstance(S, _Transposed):
        return np.asarray((S.T @ w_a.T).T), np.asarray((S.T @ w_b.T).T)
    if sp.issparse(S):
        return level_sums(_Transposed(S.T.tocsr()), w_a, w_b)
    return w_a @ S, w_b @ S


class _Transposed:
    """A sparse S held as its csr transpose (D, U), so that every batch's product is S^T @ W^T."""

    def __init__(self, T):
        self.T = T


def _prepared(S):
    return _Transposed(S.T.tocsr()) if sp.issparse(S) else S


def _observed(design):
    g = design.group.astype(np.float64)[None, :]
    return 1.0 - g, g


def run_families(design, families: list[Family], *, n_permutations: int = 4999, n_bootstrap: int = 1000,
                 confidence: float = 0.95, random_state=0, progress=None) -> list[FamilyResult]:
    """Estimates of every family's statistics; with a testable design, their p-values and intervals.

    Parameters
    ----------
    design : engine.comparison.design.Design
    families : list of Family
    n_permutations, n_bootstrap : int
    confidence : float
        Level of the percentile bootstrap intervals.
    random_state : int or numpy Generator
    progress : callable(stage, done, total) or None

    Returns
    -------
    list of FamilyResult, one per family (p and intervals NaN when the design is not testable).
    """
    rng = np.random.default_rng(random_state)
    w_a, w_b = _observed(design)
    mats = [_prepared(f.S) for f in families]
    est, obs = [], []
    for f, S in zip(families, mats):
        sa, sb = level_sums(S, w_a, w_b)
        e, t = f.statistic(sa, sb)
        e, t = np.asarray(e, np.float64)[0], np.asarray(t, np.float64)[0]
        est.append(np.where(np.isfinite(e), e, np.nan))
        obs.append(np.where(np.isfinite(t), t, np.nan))
    m = [len(e) for e in est]
    nan = [np.full(k, np.nan) for k in m]
    if not design.testable:
        return [FamilyResult(f.name, e, n.copy(), n.copy(), n.copy(), 0, False) for f, e, n in zip(families, est, nan)]

    exact = is_exact(design, n_permutations)
    n_perm = design.n_arrangements if exact else int(n_permutations)
    exceed = [np.zeros(k, np.int64) for k in m]
    valid = [np.zeros(k, np.int64) for k in m]
    done = 0
    report(progress, "permutations", 0, n_perm)
    for wb in permutation_draws(design, n_permutations, rng):
        wa = 1.0 - wb
        for i, f in enumerate(families):
            sa, sb = level_sums(mats[i], wa, wb)
            t = np.asarray(f.statistic(sa, sb)[1], np.float64)
            ok = np.isfinite(t)
            exceed[i] += (ok & (t >= obs[i] - _TIES * np.abs(obs[i]))).sum(axis=0)
            valid[i] += ok.sum(axis=0)
        done += len(wb)
        report(progress, "permutations", done, n_perm)
    ps = []
    for i in range(len(families)):
        with np.errstate(invalid="ignore", divide="ignore"):
            p = exceed[i] / valid[i] if exact else (1.0 + exceed[i]) / (1.0 + valid[i])
        p = np.where(np.isfinite(obs[i]) & (valid[i] > 0), np.minimum(p, 1.0), np.nan)
        ps.append(p)

    lows, highs = [n.copy() for n in nan], [n.copy() for n in nan]
    if design.can_bootstrap and n_bootstrap > 0:
        draws: list[list[Any]] = [[] for _ in families]
        done = 0
        report(progress, "bootstrap", 0, n_bootstrap)
        for ba, bb in bootstrap_draws(design, n_bootstrap, rng):
            for i, f in enumerate(families):
                sa, sb = level_sums(mats[i], ba, bb)
                draws[i].append(np.asarray(f.statistic(sa, sb)[0], np.float32))
            done += len(ba)
            report(progress, "bootstrap", done, n_bootstrap)
        tail = 50.0 * (1.0 - confidence)
        for i in range(len(families)):
            D = np.concatenate(draws[i], axis=0)
            D[~np.isfinite(D)] = np.nan  # a draw repeating one member: a zero spread, an infinite ratio
            enough = np.isfinite(D).sum(axis=0) >= 0.5 * len(D)
            if enough.any():
                lo, hi = np.nanpercentile(D[:, enough], [tail, 100.0 - tail], axis=0)
                lows[i][enough], highs[i][enough] = lo, hi
    return [FamilyResult(f.name, est[i], lows[i], highs[i], ps[i], int(n_perm), bool(exact))
            for i, f in enumerate(families)]


def bh_qvalues(p) -> np.ndarray:
    """Benjamini-Hochberg adjusted p-values (q) of ``p``; NaN entries stay NaN and do not count."""
    p = np.asarray(p, dtype=np.float64)
    q = np.full(p.shape, np.nan)
    ok = np.isfinite(p)
    n = int(ok.sum())
    if n:
        pv = p[ok]
        order = np.argsort(pv)
        ranked = pv[order] * n / np.arange(1, n + 1)
        adj = np.minimum.accumulate(ranked[::-1])[::-1]
        out = np.empty(n)
        out[order] = np.minimum(adj, 1.0)
        q[ok] = out
    return q
