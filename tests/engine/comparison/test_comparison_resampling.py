"""Permutations and bootstrap draws of whole units, as utterance weights."""
import itertools

import numpy as np

from engine.comparison.design import resolve_design
from engine.comparison.resampling import bootstrap_draws, is_exact, permutation_draws


def _all(gen):
    return np.concatenate(list(gen), axis=0)


def test_exact_enumeration_yields_every_arrangement_once_within_strata():
    levels = ["a", "b", "a", "b", "b", "a", "a"]
    speakers = ["S1", "S1", "S1", "S2", "S2", "S2", "S2"]
    d = resolve_design(levels, "a", "b", by="emotion", speakers=speakers)
    assert d.n_arrangements == 3 * 6 and is_exact(d, 100)
    w = _all(permutation_draws(d, 100, np.random.default_rng(0), batch=5))
    assert w.shape == (18, 7)
    assert len({tuple(r) for r in w}) == 18  # all different
    s1, s2 = d.unit_stratum == 0, d.unit_stratum == 1
    assert (w[:, s1].sum(1) == 1).all() and (w[:, s2].sum(1) == 2).all()  # each stratum keeps its count of b
    assert any((r == d.group).all() for r in w)  # the observed arrangement is one of them


def test_random_permutations_keep_each_stratum_count_and_vary():
    levels = ["a", "b"] * 10
    texts = np.repeat([f"t{i}" for i in range(10)], 2)
    d = resolve_design(levels, "a", "b", pairs=texts, paired_by="text")
    assert not is_exact(d, 500)
    w = _all(permutation_draws(d, 500, np.random.default_rng(1), batch=128))
    assert w.shape == (500, 20)
    pairs = w.reshape(500, 10, 2).sum(-1)
    assert (pairs == 1).all()
    assert 0.4 < w[:, 0].mean() < 0.6


def test_whole_speakers_move_together():
    levels = ["F"] * 6 + ["M"] * 6
    speakers = np.repeat(["s1", "s2", "s3", "s4", "s5", "s6"], 2)
    d = resolve_design(levels, "F", "M", by="sex", speakers=speakers)
    w = _all(permutation_draws(d, 1000, np.random.default_rng(2)))
    assert w.shape == (20, 12)  # C(6, 3) arrangements of whole speakers
    assert (w[:, 0::2] == w[:, 1::2]).all()


def test_bootstrap_cells_and_blocks():
    d = resolve_design(["a"] * 4 + ["b"] * 3, "a", "b")
    for wa, wb in bootstrap_draws(d, 300, np.random.default_rng(3), batch=100):
        assert (wa[:, 4:] == 0).all() and (wb[:, :4] == 0).all()
        assert (wa.sum(1) == 4).all() and (wb.sum(1) == 3).all()
    texts = np.repeat(["t1", "t2", "t3", "t4"], 2)
    d = resolve_design(["a", "b"] * 4, "a", "b", pairs=texts, paired_by="text")
    wa, wb = next(bootstrap_draws(d, 200, np.random.default_rng(4)))
    assert (wa[:, 0::2] == wb[:, 1::2]).all()  # a block is drawn whole
    assert (wa.sum(1) == 4).all()
    assert len({tuple(r) for r in wa}) > 10


def test_exact_enumeration_matches_itertools():
    d = resolve_design(["a", "a", "b", "b", "b"], "a", "b")
    w = _all(permutation_draws(d, 10, np.random.default_rng(0)))
    want = {tuple(int(i in c) for i in range(5)) for c in itertools.combinations(range(5), 3)}
    assert {tuple(int(x) for x in r) for r in w} == want
