"""Paired per-utterance comparison of two methods: mean difference, bootstrap CI, sign test.

Two synthesis methods scored on the same held-out utterances give one error per
utterance each. Their per-utterance differences ``d_u = e_baseline - e_reference``
(positive: the reference method erred less on that utterance) are summarised by

* the mean difference and a percentile bootstrap confidence interval of it
  (utterances resampled with replacement, seeded, so the interval is reproducible);
* the sign test: the number of utterances the reference wins and loses (ties, exact
  equality, are dropped) and the two-sided binomial p-value of that split under
  "each side wins half the time" (:func:`scipy.stats.binomtest`);
* the Wilcoxon signed-rank test of the differences (two-sided, :func:`scipy.stats.wilcoxon`;
  zero differences dropped), which also weighs how large each win or loss is.

The sign test makes no assumption about the size or distribution of the differences;
the signed-rank test assumes them symmetric about their median; the bootstrap interval
describes their size.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["PairedComparison", "paired_comparison"]


@dataclass(frozen=True)
class PairedComparison:
    """Summary of the per-utterance differences ``baseline - reference``.

    Attributes
    ----------
    n : int
        Utterances compared.
    mean_diff : float
        Mean of ``e_baseline - e_reference`` (> 0: the reference is better on average).
    ci_low, ci_high : float
        Percentile bootstrap interval of the mean difference (``confidence`` level);
        NaN with fewer than 2 utterances.
    wins, losses : int
        Utterances where the reference erred less / more (ties excluded).
    p_sign : float
        Two-sided sign-test p-value (1.0 when every utterance ties).
    confidence : float
    p_wilcoxon : float
        Two-sided signed-rank p-value (1.0 when every utterance ties).
    """

    n: int
    mean_diff: float
    ci_low: float
    ci_high: float
    wins: int
    losses: int
    p_sign: float
    confidence: float
    p_wilcoxon: float = 1.0

    def as_dict(self) -> dict:
        return asdict(self)


def paired_comparison(reference, baseline, *, n_boot=2000, confidence=0.95, random_state=0) -> PairedComparison:
    """Compare per-utterance errors of a reference method against a baseline.

    Parameters
    ----------
    reference, baseline : array-like of shape (n,)
        Errors of the two methods on the same n utterances, in the same order.
    n_boot : int, default=2000
        Bootstrap resamples.
    confidence : float, default=0.95
    random_state : int, default=0

    Returns
    -------
    PairedComparison
    """
    from scipy.stats import binomtest, wilcoxon

    a = np.asarray(reference, dtype=np.float64).reshape(-1)
    b = np.asarray(baseline, dtype=np.float64).reshape(-1)
    if a.shape != b.shape:
        raise ValueError(f"reference and baseline must hold one error per utterance each; got {a.size} and {b.size}")
    if not np.all(np.isfinite(a)) or not np.all(np.isfinite(b)):
        raise ValueError("per-utterance errors must be finite (an utterance some method could not synthesise "
                         "must be dropped from both)")
    if not 0 < float(confidence) < 1:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")
    if int(n_boot) < 1:
        raise ValueError(f"n_boot must be >= 1, got {n_boot}")
    d = b - a
    n = d.size
    if n == 0:
        raise ValueError("no utterances to compare")
    wins, losses = int((d > 0).sum()), int((d < 0).sum())
    p = float(binomtest(wins, wins + losses, 0.5).pvalue) if wins + losses else 1.0
    pw = float(wilcoxon(d[d != 0]).pvalue) if wins + losses else 1.0
    if n >= 2:
        rng = np.random.default_rng(random_state)
        means = d[rng.integers(0, n, size=(int(n_boot), n))].mean(axis=1)
        alpha = (1 - float(confidence)) / 2
        lo, hi = np.quantile(means, [alpha, 1 - alpha])
    else:
        lo = hi = float("nan")
    return PairedComparison(n=n, mean_diff=float(d.mean()), ci_low=float(lo), ci_high=float(hi), wins=wins,
                            losses=losses, p_sign=p, confidence=float(confidence), p_wilcoxon=pw)
