"""How real the synthetic talker looks to the method: scree, embedding variance, class agreement.

:func:`talker_realism` measures a fitted :class:`engine.manifold.Manifold` of a corpus
that carries the synthetic talker's exact ground truth (``Corpus.latent``: the
``aperture`` of the noise-free surface and its gesture ``phase``,
:func:`engine.synthetic.gesture_phases`):

* the X scree: components needed for 80 / 95 / 99 % of the total variance of the
  frames, and of the variance of the computed components (the paper's "recovered
  variance": 95 % in 10, 99 % in 30 on real lips);
* the variance the first three embedding dimensions Y1-3 hold (the paper: 93 %);
* the agreement of the tangent frames' four movement classes with the ground-truth
  phases, next to the agreement of the trivial rule that reads the same classes off
  the frame-to-frame change of F^x_1 alone (no manifold), on the same frames.

Scored frames: a forward and a backward step inside the utterance, and a true aperture
speed above its 20th percentile (nearly still lips have no meaningful phase).
"""
from __future__ import annotations

import numpy as np

__all__ = ["talker_realism", "components_for", "rule_classes", "format_realism"]


def components_for(ratios, fractions=(0.80, 0.95, 0.99)) -> tuple[int, ...]:
    """Smallest number of leading components whose variance ``ratios`` reach each fraction
    of ``ratios.sum()``.

    Parameters
    ----------
    ratios : ndarray of shape (k,)
        Variance per component, largest first.
    fractions : sequence of float in (0, 1]
    """
    r = np.asarray(ratios, np.float64)
    if r.ndim != 1 or len(r) == 0 or not np.isfinite(r).all() or (r < 0).any():
        raise ValueError(f"ratios must be a non-empty 1-D array of variances >= 0, got shape {r.shape}")
    cum = np.cumsum(r)
    return tuple(int(np.searchsorted(cum, f * cum[-1] - 1e-12) + 1) for f in fractions)


def _steps(x, bounds):
    """(forward step, backward step, has both) per frame inside utterances."""
    x = np.asarray(x, np.float64)
    n = len(x)
    fwd, back = np.zeros(n), np.zeros(n)
    fwd[:-1] = x[1:] - x[:-1]
    back[1:] = x[1:] - x[:-1]
    ok = np.ones(n, bool)
    b = np.asarray(bounds)
    ok[b[:, 1] - 1] = False
    ok[b[:, 0]] = False
    return fwd, back, ok


def rule_classes(x, bounds) -> tuple[np.ndarray, np.ndarray]:
    """The trivial rule's (opening, accelerating) per frame from a signal ``x`` (n,):
    opening iff the forward step is positive, accelerating iff ``sign(step - previous
    step) == sign(step)`` (the engine's convention)."""
    fwd, back, _ = _steps(x, bounds)
    return fwd > 0, np.sign(fwd - back) == np.sign(fwd)


def talker_realism(manifold) -> dict:
    """Scree, Y variance and class agreement of a fitted manifold of a synthetic corpus.

    Parameters
    ----------
    manifold : engine.manifold.Manifold
        Fitted on a corpus whose ``latent`` holds ``aperture`` (the synthetic talker's).

    Returns
    -------
    dict
        ``x_total`` (components for 80/95/99 % of the total variance; None where the
        computed components do not reach it), ``x_recovered``
        (the same of the computed components), ``x_computed`` (how many were computed),
        ``scree`` (first ten fractions of the total), ``y3`` (fraction of the embedding's
        variance in Y1-3), ``sign`` (+1 when the aperture grows with F^x_1), ``scored``
        (frames scored) and, for ``method`` and ``rule``, the agreement of ``opening``,
        ``accelerating`` and all four ``classes`` with the ground truth.

    Raises
    ------
    ValueError
        When the corpus carries no ``aperture`` ground truth.
    """
    corpus = manifold.corpus_
    if "aperture" not in corpus.latent:
        raise ValueError(f"corpus {corpus.name!r} has no ground-truth 'aperture' in its latent variables; "
                         "this report needs the synthetic talker (engine.synthetic)")
    sh = manifold.shape_
    scree = np.asarray(sh.scree_, np.float64)
    out = {"x_recovered": components_for(scree), "x_computed": len(scree),
           "scree": [float(v) for v in scree[:10]]}
    # of the total: None where the computed components do not reach the fraction
    cum = np.cumsum(scree)
    out["x_total"] = tuple(int(np.searchsorted(cum, f - 1e-12) + 1) if cum[-1] >= f else None
                           for f in (0.80, 0.95, 0.99))
    ev = np.asarray(manifold.embedding_.explained_variance_ratio_, np.float64)
    out["y3"] = float(ev[:3].sum())
    bounds = corpus.bounds
    ap = np.asarray(corpus.latent["aperture"], np.float64)
    fx1 = np.asarray(manifold.Fx_[:, 0], np.float64)
    sign = float(np.sign(np.corrcoef(ap, fx1)[0, 1])) or 1.0
    out["sign"] = sign
    t_open, t_acc = rule_classes(sign * ap, bounds)
    fwd, _, ok = _steps(ap, bounds)
    speed = np.abs(fwd)
    scored = ok & (speed > np.quantile(speed[ok], 0.20))
    out["scored"] = int(scored.sum())
    tf = manifold.tangent_
    r_open, r_acc = rule_classes(fx1, bounds)
    for name, (o, a) in (("method", (tf.opening_, tf.accelerating_)), ("rule", (r_open, r_acc))):
        o, a = np.asarray(o, bool), np.asarray(a, bool)
        out[name] = {"opening": float((o == t_open)[scored].mean()),
                     "accelerating": float((a == t_acc)[scored].mean()),
                     "classes": float(((o == t_open) & (a == t_acc))[scored].mean())}
    return out


def format_realism(r: dict) -> list[str]:
    """Plain-text lines of a :func:`talker_realism` result."""
    tot = ", ".join("-" if v is None else str(v) for v in r["x_total"])
    lines = [f"X scree: components for 80/95/99 % of the total variance: {tot}; of the {r['x_computed']} computed "
             f"components' variance: {', '.join(map(str, r['x_recovered']))}",
             "X scree, first ten (% of total): " + " ".join(f"{100 * v:.2f}" for v in r["scree"]),
             f"Y1-3 hold {100 * r['y3']:.1f} % of the embedding's variance",
             f"class agreement with the ground truth on {r['scored']} moving frames (aperture sign {r['sign']:+.0f}):"]
    for name, label in (("method", "tangent classes"), ("rule", "Delta F^x_1 rule")):
        m = r[name]
        lines.append(f"  {label:16s} opening {100 * m['opening']:.1f} %, accelerating {100 * m['accelerating']:.1f} %, "
                     f"all four classes {100 * m['classes']:.1f} %")
    return lines
