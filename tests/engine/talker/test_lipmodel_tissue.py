"""The lip tissue's own variation: vermilion roll and the chin's mentalis (engine.talker.lipmodel),
and the talker's opt-in tissue variation (``SyntheticTalker(tissue=True)``): phone targets
of the two controls, token-to-token size of the lip gestures (engine.talker.synthetic)."""
from __future__ import annotations

import numpy as np
import pytest

import engine.talker.synthetic_talker as synthetic
from engine.talker.lipmodel import CONTROL_NAMES, LipModel
from engine.talker.synthetic import SyntheticTalker


def _controls(**kw):
    c = np.zeros((1, len(CONTROL_NAMES)))
    for k, v in kw.items():
        c[0, CONTROL_NAMES.index(k)] = v
    return c


@pytest.fixture(scope="module")
def lip():
    return LipModel("default")


def _grid(lip, **kw):
    """Points (2, rows, cols, 3) of the surface for the given controls."""
    return lip.deform(_controls(**kw)).reshape(2, lip.rows, lip.cols, 3)


def _border_row(lip):
    """Index of the last vermilion row (t <= 0.4)."""
    t = np.linspace(0.0, 1.0, lip.rows) ** 1.4
    return int(np.flatnonzero(t <= 0.4)[-1])


@pytest.mark.parametrize("jaw", [0.0, 0.7])
def test_roll_everts_and_inverts_the_vermilion_only(lip, jaw):
    rest, out, inn = _grid(lip, jaw=jaw), _grid(lip, jaw=jaw, roll=1.0), _grid(lip, jaw=jaw, roll=-1.0)
    mid, b = lip.cols // 2, _border_row(lip)
    # the inner contour (row 0 of both lips) does not move: the aperture is the same
    np.testing.assert_allclose(out[:, 0], rest[:, 0], atol=1e-4)
    np.testing.assert_allclose(inn[:, 0], rest[:, 0], atol=1e-4)
    assert lip.aperture(_controls(jaw=jaw, roll=1.0))[0] == pytest.approx(lip.aperture(_controls(jaw=jaw))[0])
    # visible red lip on the midline: taller everted, shorter inverted, by about 30 %
    h = {k: (g[0, b, mid, 1] - g[0, 0, mid, 1], g[1, 0, mid, 1] - g[1, b, mid, 1])
         for k, g in (("rest", rest), ("out", out), ("in", inn))}
    for lipk in (0, 1):
        assert h["out"][lipk] > 1.15 * h["rest"][lipk] and h["in"][lipk] < 0.85 * h["rest"][lipk]
    # the vermilion border goes forward when everted, back when inverted (mm)
    assert (out[:, b, mid, 2] - rest[:, b, mid, 2] > 1.0).all()
    assert (rest[:, b, mid, 2] - inn[:, b, mid, 2] > 1.0).all()
    # rows stay in order down the midline (no row passes the next)
    for g in (out, inn):
        assert (np.diff(g[0, :, mid, 1]) > 0).all() and (np.diff(g[1, :, mid, 1]) < 0).all()


def test_mentalis_raises_the_chin_not_the_inner_lip(lip):
    rest, m = _grid(lip), _grid(lip, mentalis=1.0)
    mid, R = lip.cols // 2, lip.rows
    d = m - rest
    np.testing.assert_allclose(d[0], 0.0, atol=1e-4)            # the upper lip does not move
    np.testing.assert_allclose(d[1, 0], 0.0, atol=1e-4)         # nor the lower inner contour
    assert 2.5 < d[1, R - 1, mid, 1] <= 3.0 + 1e-4              # chin up ~3 mm
    assert 1.0 < d[1, R - 1, mid, 2] <= 1.5 + 1e-4              # and forward ~1.5 mm
    b = _border_row(lip)
    assert 0.5 < d[1, b, mid, 1] and 0.5 < d[1, b, mid, 2]      # lower vermilion pushed up and out
    # the mentolabial sulcus deepens: the deepest skin point goes back relative to its neighbours
    z = lambda g: g[1, b + 1:, mid, 2]  # noqa: E731
    depth = lambda g: 0.5 * (z(g)[0] + z(g)[-1]) - z(g).min()  # noqa: E731
    assert depth(m) > depth(rest) + 1.0
    assert (np.diff(m[1, :, mid, 1]) < 0).all()                 # rows stay in order


# --------------------------------------------------------------- the generator
@pytest.fixture(scope="module")
def talker():
    return SyntheticTalker(preset="small", n_sentences=60, tissue=True).generate()


def test_without_tissue_variation_roll_and_mentalis_stay_still(small_corpus):
    assert not small_corpus.latent["roll"].any() and not small_corpus.latent["mentalis"].any()
    with pytest.raises(ValueError, match="tissue must be True or False"):
        SyntheticTalker(tissue="yes").generate()


def _midpoints(corpus, phones):
    idx = []
    for u in corpus.utterances:
        for p in u.phones:
            if p.label in phones:
                idx.append(u.start + int(round(0.5 * (p.start + p.end) * corpus.rate)))
    return np.array(idx)


def test_bilabials_press_the_lips_in_and_raise_the_chin_postalveolars_evert(talker):
    lat = talker.latent
    bil, sh, vow = (_midpoints(talker, s) for s in (("p", "b", "m"), ("sh", "ch", "jh", "zh"), ("aa", "ae", "ah")))
    assert len(bil) > 30 and len(sh) > 5 and len(vow) > 30
    assert lat["roll"][bil].mean() < -0.2 < 0.2 < lat["roll"][sh].mean()
    assert lat["mentalis"][bil].mean() > lat["mentalis"][vow].mean() + 0.1


def _sizes(monkeypatch, token_sd):
    monkeypatch.setattr(synthetic, "_TOKEN_SD", token_sd)
    c = SyntheticTalker(preset="small", n_sentences=40, jitter=0.0, tissue=True).generate()
    mid = _midpoints(c, ("uw", "w"))
    return c.latent["round"][mid], c.latent["protrude"][mid]


def test_token_variability_lets_rounding_and_protrusion_vary_apart(monkeypatch):
    # each token's rounding and protrusion are scaled by their own factor: at the
    # mid-points of /uw w/ the two no longer move as one. The same seed with the factors
    # at 1 (and the jitter off) draws the same sentences, where only coarticulation and
    # emphasis part them; the factors add variance to log(protrude / round).
    # Measured: s.d. 0.200 without, 0.291 with (added variance 0.045; the factors alone,
    # before blending and dynamics, would add 2 * 0.25**2 = 0.125)
    token_sd = synthetic._TOKEN_SD
    r0, p0 = _sizes(monkeypatch, 0.0)
    r1, p1 = _sizes(monkeypatch, token_sd)
    spread0, spread1 = np.std(np.log(p0 / r0)), np.std(np.log(p1 / r1))
    assert spread1 ** 2 - spread0 ** 2 > 0.025
