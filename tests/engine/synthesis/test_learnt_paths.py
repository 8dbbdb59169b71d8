"""Learnt gap paths: the training sub-trajectories between two points of F^y, and their validated blend."""

import numpy as np
import pytest

from engine.synthesis.learnt_paths import BASES, NEIGHBOR_STEPS, BlendAccumulator, LearntPaths, blend, fit_blend
from engine.synthesis.trajectory import interpolate_targets

#: one transition: 12 frames of a tanh step from about -1 to about +1
STEP = np.tanh(np.linspace(-2.5, 2.5, 12))


def _steps_corpus(n_utt=30, seed=0):
    """Utterances that swing between about -1 and +1, each swing a tanh step of 12 frames.

    Y = (x, velocity), so a turning point (velocity 0) and mid-swing are distinct points; X = (x, 0.5 x).
    """
    rng = np.random.default_rng(seed)
    Ys, Xs, bounds, start = [], [], [], 0
    for _ in range(n_utt):
        x = np.concatenate([STEP if k % 2 == 0 else -STEP for k in range(8)])
        x = x + rng.normal(0, 0.005, len(x))
        v = np.gradient(x)
        Ys.append(np.column_stack([x, 4 * v]))
        Xs.append(np.column_stack([x, 0.5 * x]))
        bounds.append([start, start + len(x)])
        start += len(x)
    return np.vstack(Ys), np.vstack(Xs), np.array(bounds)


def test_pooled_path_recovers_the_transition_shape_hermite_misses():
    """Between the turning point at -1 and the one at +1, 11 frames later, the real path is a tanh step; the
    pooled training paths reproduce it, the cubic Hermite spline with the turning points' (zero) velocity does not."""
    Y, X, b = _steps_corpus()
    lab = (Y[:, 0] > 0).astype(int)
    C = np.array([[STEP[0], 0.0], [STEP[-1], 0.0]])
    lp = LearntPaths(n_pool=64).fit(Y, X, b, lab, C)
    n = 11
    P = lp.gap_means(C[0], C[1], n, neighbors=(16,))[0]
    truth = STEP
    H = interpolate_targets("hermite", [0, n], np.array([[STEP[0], 0.5 * STEP[0]], [STEP[-1], 0.5 * STEP[-1]]]),
                            n + 1, np.zeros((2, 2)))
    e_p = np.sqrt(((P[:, 0] - truth) ** 2).mean())
    e_h = np.sqrt(((H[:, 0] - truth) ** 2).mean())
    assert e_p < 0.5 * e_h, (e_p, e_h)
    np.testing.assert_allclose(P[:, 1], 0.5 * P[:, 0], atol=1e-9)  # every component from the same segments
    # no segment crosses an utterance boundary: every candidate lies inside one utterance
    s, e, _ = lp._candidates(C[0], C[1], n)
    u_s = np.searchsorted(b[:, 1], s, side="right")
    u_e = np.searchsorted(b[:, 1], e, side="right")
    assert np.all(u_s == u_e)


def test_pooled_through_targets_and_anchoring():
    Y, X, b = _steps_corpus(10)
    lab = (Y[:, 0] > 0).astype(int)
    C = np.array([[STEP[0], 0.0], [STEP[-1], 0.0]])
    lp = LearntPaths().fit(Y, X, b, lab, C)
    f = np.array([3, 14, 25])
    pts = C[[0, 1, 0]]
    xt = np.array([[-0.9, -0.4], [1.1, 0.6], [-1.0, -0.5]])
    P = lp.pooled(f, pts, 50, neighbors=(8, 32), x_targets=xt)
    assert P.shape == (2, 50, 2)
    np.testing.assert_allclose(P[:, f], np.repeat(xt[None], 2, axis=0), atol=1e-12)  # pulled onto the targets
    np.testing.assert_allclose(P[:, :3], np.repeat(P[:, 3:4], 3, axis=1))  # the first target held before it
    with pytest.raises(ValueError, match="at least one transition"):
        lp.gap_means(C[0], C[1], 0)


def test_fit_blend_recovers_the_base_and_share_and_never_leaves_zero_to_one():
    rng = np.random.default_rng(3)
    n, m = 400, 4
    B = rng.normal(size=(len(BASES), n, m))
    P = np.stack([B[0] + rng.normal(size=(n, m)) for _ in NEIGHBOR_STEPS])
    # component 0 halfway from the first base to neighbour step 2; 1 the first base; 2 beyond step 4;
    # 3 the third base with no learnt share
    truth = B[0].copy()
    truth[:, 0] += 0.5 * (P[2, :, 0] - B[0, :, 0])
    truth[:, 2] += 1.8 * (P[4, :, 2] - B[0, :, 2])
    truth[:, 3] = B[2, :, 3]
    acc = BlendAccumulator(len(BASES), len(NEIGHBOR_STEPS), m)
    acc.add(B, P, truth + rng.normal(0, 0.01, (n, m)))
    w = fit_blend(acc)
    assert [w["base_index"][j] for j in (0, 1, 3)] == [0, 0, 2]
    assert w["neighbor_index"][0] == 2 and w["beta"][0] == pytest.approx(0.5, abs=0.01)
    assert w["beta"][1] == pytest.approx(0.0, abs=0.02) and w["beta"][3] == pytest.approx(0.0, abs=0.02)
    assert all(0.0 <= b <= 1.0 for b in w["beta"]) and w["beta"][2] == 1.0  # a share, never an extrapolation
    out = blend(B, P, w["base_index"], w["neighbor_index"], w["beta"])
    np.testing.assert_allclose(out[:, 0], B[0, :, 0] + w["beta"][0] * (P[2, :, 0] - B[0, :, 0]))
    assert sum(w["sq_error"]) < np.min(np.sum(w["sq_bases"], axis=1))


def test_fit_blend_over_utterances_chooses_by_leaving_each_one_out():
    """Given one accumulator per validation utterance, a share that fits one utterance's own noise is not
    bought: the component keeps its base alone, where the fit on all frames pooled takes a share of it."""
    rng = np.random.default_rng(4)
    n, m, U = 80, 2, 4
    accs, pooled = [], BlendAccumulator(len(BASES), len(NEIGHBOR_STEPS), m)
    for u in range(U):
        B = rng.normal(size=(len(BASES), n, m))
        noise = rng.normal(0, 0.3, (n, m))
        truth = B[1] + noise  # both components: the second base
        P = np.stack([B[1] + rng.normal(0, 1, (n, m)) for _ in NEIGHBOR_STEPS])
        truth[:, 0] += 0.6 * (P[3, :, 0] - B[1, :, 0])  # component 0 also takes a real share of step 3
        # component 1's pooled paths: the first utterance's own noise there, unrelated noise elsewhere
        P[:, :, 1] = B[1, :, 1] + (noise[:, 1] if u == 0 else rng.normal(0, 0.3, (len(NEIGHBOR_STEPS), n)))
        a = BlendAccumulator(len(BASES), len(NEIGHBOR_STEPS), m)
        a.add(B, P, truth)
        accs.append(a)
        pooled.add(B, P, truth)
    cv, fitted = fit_blend(accs), fit_blend(pooled)
    assert cv["frames"] == fitted["frames"] == U * n
    assert cv["base_index"] == [1, 1] and cv["neighbor_index"][0] == 3
    assert cv["beta"][0] == pytest.approx(0.6, abs=0.05)
    assert cv["beta"][1] == 0.0 and fitted["beta"][1] > 0.1  # bought on all frames pooled, not when left out
    assert cv["sq_error"][1] == pytest.approx(cv["sq_bases"][1][1])  # the base alone, scored as such
    assert all(c >= f - 1e-9 for c, f in zip(cv["sq_error"], fitted["sq_error"]))  # left out never looks better
