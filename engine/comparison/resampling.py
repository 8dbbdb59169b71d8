"""Resampling whole units: permutations of the level labels and bootstrap draws, as utterance weights.

Every statistic of a comparison is a function of per-utterance sums taken over each level
(:mod:`engine.comparison.statistics`), so one draw is a pair of weight vectors over the
design's utterances: how many times each utterance counts in level a and in level b. A
permutation gives 0/1 weights (the permuted labels); a bootstrap draw gives counts.

* :func:`permutation_draws`: the labels of the units permuted within their strata. When the
  design has at most ``n`` distinct arrangements every one is enumerated (an exact test;
  the observed arrangement is among them); otherwise ``n`` are drawn at random.
* :func:`bootstrap_draws`: units drawn with replacement within each (stratum, level) cell,
  or whole strata (blocks) with replacement for a paired design.
"""
from __future__ import annotations

import itertools
from collections.abc import Iterator

import numpy as np

__all__ = ["permutation_draws", "bootstrap_draws", "is_exact", "DEFAULT_BATCH"]

#: draws per batch (the weights of a batch are (batch, U) float64)
DEFAULT_BATCH = 256


def is_exact(design, n_permutations: int) -> bool:
    """Whether :func:`permutation_draws` enumerates every arrangement (an exact test)."""
    return design.n_arrangements <= int(n_permutations)


def _strata(design):
    return [np.flatnonzero(design.unit_stratum == s) for s in range(design.n_strata)]


def _to_utterances(design, unit_labels: np.ndarray) -> np.ndarray:
    """(b, n_units) 0/1 labels of units -> (b, U) weights of level b over the design's utterances."""
    return unit_labels[:, design.unit].astype(np.float64)


def permutation_draws(design, n_permutations: int, rng: np.random.Generator, *,
                      batch: int = DEFAULT_BATCH) -> Iterator[np.ndarray]:
    """Yield batches of level-b weights, shape (b, U), of permuted labels.

    Exact enumeration (:func:`is_exact`) yields every arrangement once; otherwise
    ``n_permutations`` random permutations (within strata).
    """
    n_units = len(design.unit_group)
    strata = _strata(design)
    if is_exact(design, n_permutations):
        per = []
        for idx in strata:
            m = int(design.unit_group[idx].sum())
            per.append([np.asarray(c, dtype=np.int64) for c in itertools.combinations(idx, m)])
        combos = itertools.product(*per)
        while True:
            chunk = list(itertools.islice(combos, batch))
            if not chunk:
                return
            labels = np.zeros((len(chunk), n_units), dtype=np.int8)
            for r, parts in enumerate(chunk):
                for c in parts:
                    labels[r, c] = 1
            yield _to_utterances(design, labels)
    done = 0
    while done < n_permutations:
        b = min(batch, n_permutations - done)
        labels = np.zeros((b, n_units), dtype=np.int8)
        for idx in strata:
            m = int(design.unit_group[idx].sum())
            if m == 0 or m == len(idx):
                labels[:, idx] = 1 if m else 0
                continue
            order = np.argsort(rng.random((b, len(idx))), axis=1)[:, :m]
            np.put_along_axis(labels, idx[order], 1, axis=1)
        done += b
        yield _to_utterances(design, labels)


def _counts(rng, n_draws: int, n: int) -> np.ndarray:
    """(n_draws, n) counts of n items drawn with replacement n times, per draw."""
    picks = rng.integers(0, n, size=(n_draws, n))
    flat = picks + (np.arange(n_draws)[:, None] * n)
    return np.bincount(flat.ravel(), minlength=n_draws * n).reshape(n_draws, n)


def bootstrap_draws(design, n_bootstrap: int, rng: np.random.Generator, *,
                    batch: int = DEFAULT_BATCH) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Yield batches ``(w_a, w_b)`` of bootstrap weights, each (b, U): how often each utterance counts in
    level a and in level b of one draw."""
    g = design.group.astype(np.float64)
    done = 0
    while done < n_bootstrap:
        b = min(batch, n_bootstrap - done)
        if design.bootstrap == "blocks":
            w_stratum = _counts(rng, b, design.n_strata).astype(np.float64)
            w_unit = w_stratum[:, design.unit_stratum]
        else:
            w_unit = np.zeros((b, len(design.unit_group)))
            for s in range(design.n_strata):
                for lv in (0, 1):
                    idx = np.flatnonzero((design.unit_stratum == s) & (design.unit_group == lv))
                    if idx.size:
                        w_unit[:, idx] = _counts(rng, b, idx.size)
        w = w_unit[:, design.unit]
        done += b
        yield w * (1.0 - g), w * g
