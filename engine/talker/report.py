"""How real the synthetic talker looks to the method: scree, embedding variance, class agreement.

:func:`talker_realism` measures a fitted :class:`engine.manifold.model.Manifold` of a corpus
that carries the synthetic talker's exact ground truth (``Corpus.latent``: the
``aperture`` of the noise-free surface and its gesture ``phase``,
:func:`engine.talker.synthetic.gesture_phases`):

* the X scree: components needed for 80 / 95 / 99 % of the total variance of the
  frames, and of the variance of the computed components (the paper's "recovered
  variance": 95 % in 10, 99 % in 30 on real lips);
* the variance the first three embedding dimensions Y1-3 hold (the paper: 93 %);
* the agreement of the tangent frames' four movement classes with the ground-truth
  phases, next to the agreement of the trivial rule that reads the same classes off
  the frame-to-frame change of F^x_1 alone (no manifold), on the same frames.

Scored frames: a forward and a backward step inside the utterance, and a true aperture
speed above its 20th percentile (nearly still lips have no meaningful phase).

:func:`articulation_report` says where the X scree comes from: what the talker's
controls alone make of the lip surface (no capture noise, no registration error), how
much of that variance each control brings, how often each moves, and which move together.
"""
from __future__ import annotations

import numpy as np

__all__ = ["talker_realism", "components_for", "components_of_total", "rule_classes", "format_realism",
           "articulation_report", "format_articulation"]


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


def components_of_total(scree, fractions=(0.80, 0.95, 0.99)) -> tuple:
    """Smallest number of leading components whose fractions of the total variance ``scree``
    (k,) reach each fraction; None where the k computed components do not reach it."""
    cum = np.cumsum(np.asarray(scree, np.float64))
    return tuple(int(np.searchsorted(cum, f - 1e-12) + 1) if len(cum) and cum[-1] >= f else None
                 for f in fractions)


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
    manifold : engine.manifold.model.Manifold
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
                         "this report needs the synthetic talker (engine.talker.synthetic)")
    sh = manifold.shape_
    scree = np.asarray(sh.scree_, np.float64)
    out = {"x_recovered": components_for(scree), "x_computed": len(scree),
           "scree": [float(v) for v in scree[:10]]}
    out["x_total"] = components_of_total(scree)
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


_BLOCK = 4096  # frames per block


def _mean_frame(lip, controls):
    s1 = np.zeros(3 * lip.n_points)
    for a in range(0, len(controls), _BLOCK):
        s1 += lip.deform(controls[a:a + _BLOCK]).sum(0, dtype=np.float64)
    return s1 / len(controls)


def _sum_squares(lip, controls):
    """Sum of squared deviations from the mean frame of ``lip.deform(controls)``."""
    mu = _mean_frame(lip, controls)
    return sum(float(np.square(lip.deform(controls[a:a + _BLOCK]) - mu).sum(dtype=np.float64))
               for a in range(0, len(controls), _BLOCK))


def articulation_report(lip, controls, names=None, *, active=0.1, correlated=0.4) -> dict:
    """What the controls alone make of the lip surface (noise-free), per control.

    Parameters
    ----------
    lip : engine.talker.lipmodel.LipModel
        The talker's lip surface (its speaker's anatomy and resolution).
    controls : ndarray of shape (n_frames, n_controls)
        The controls per frame (``Corpus.latent``'s, in the order of ``names``).
    names : sequence of str or None
        Control names (default :data:`engine.talker.lipmodel.CONTROL_NAMES`).
    active : float
        A control counts as moving on a frame more than ``active`` from its median.
    correlated : float
        Pairs of controls whose correlation magnitude exceeds this are listed.

    Returns
    -------
    dict
        ``components`` (components for 80/95/99 % of the noise-free surface's variance),
        ``scree`` (its first ten fractions), ``share`` (per name: the variance of the
        surface when only that control moves, the others held at their mean, as a fraction
        of the noise-free variance), ``active`` (per name: fraction of frames where it
        moves) and ``pairs`` ((name, name, correlation) above ``correlated``, largest first).
    """
    from engine.talker.lipmodel import CONTROL_NAMES

    names = tuple(CONTROL_NAMES if names is None else names)
    C = np.asarray(controls, np.float64)
    if C.ndim != 2 or C.shape[1] != len(names) or len(C) < 2:
        raise ValueError(f"controls must have shape (n_frames >= 2, {len(names)}) in the order {names}, got {C.shape}")
    n, D = len(C), 3 * lip.n_points
    # the noise-free surface's covariance (D x D, D = 3 * points), accumulated over blocks
    mu = _mean_frame(lip, C).astype(np.float32)
    xtx = np.zeros((D, D))
    for a in range(0, n, _BLOCK):
        F = lip.deform(C[a:a + _BLOCK]) - mu
        xtx += F.T @ F
    ev = np.linalg.eigvalsh(xtx / (n - 1))[::-1].clip(0.0)
    total = float(ev.sum()) * (n - 1)
    mean = C.mean(0)
    share, act = {}, {}
    for k, name in enumerate(names):
        if total <= 0 or np.ptp(C[:, k]) == 0:  # a control that never moves adds nothing: no surface to deform
            share[name] = 0.0
        else:
            Ck = np.tile(mean, (n, 1))
            Ck[:, k] = C[:, k]
            share[name] = _sum_squares(lip, Ck) / total
        act[name] = float(np.mean(np.abs(C[:, k] - np.median(C[:, k])) > active))
    sd = C.std(0)
    moving = np.flatnonzero(sd > 0)
    R = np.atleast_2d(np.corrcoef(C[:, moving].T)) if len(moving) > 1 else np.ones((1, 1))
    pairs = [(names[moving[i]], names[moving[j]], float(R[i, j])) for i in range(len(moving))
             for j in range(i + 1, len(moving)) if abs(R[i, j]) > correlated]
    pairs.sort(key=lambda p: -abs(p[2]))
    return {"components": components_for(ev), "scree": [float(v) for v in (ev / ev.sum())[:10]],
            "share": share, "active": act, "pairs": pairs}


def format_articulation(r: dict) -> list[str]:
    """Plain-text lines of an :func:`articulation_report` result."""
    return [f"noise-free surface (controls alone): components for 80/95/99 % of its variance: "
            f"{', '.join(map(str, r['components']))}; scree " + " ".join(f"{100 * v:.2f}" for v in r["scree"][:7]),
            "variance share when only one control moves (% of the noise-free variance): "
            + ", ".join(f"{k} {100 * v:.1f}" for k, v in sorted(r["share"].items(), key=lambda kv: -kv[1])),
            "frames where a control moves: " + ", ".join(f"{k} {100 * v:.0f} %" for k, v in r["active"].items()),
            "controls that move together (correlation): "
            + (", ".join(f"{a}-{b} {c:+.2f}" for a, b, c in r["pairs"]) or "none")]
