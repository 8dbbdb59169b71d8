import itertools

import numpy as np
import pytest
import scipy.sparse as sp

from engine.phonetics.targets import (
    Target,
    TargetError,
    TargetSequence,
    UnknownPhoneError,
    parse_phone_string,
    targets_from_phones,
    targets_from_points,
    targets_from_text,
    targets_from_textgrid,
    targets_from_utterance,
)
from engine.synthesis.methods import make_synthesizer
from engine.synthesis.viterbi import (
    MaxProductGraph,
    NoPathError,
    Synthesizer,
    Trajectory,
    ViterbiSynthesizer,
    log_transitions,
    observed_transitions,
    viterbi_path,
)


# ---------------------------------------------------------------- Viterbi core
def _random_chain(K, rng, density=0.4):
    C = (rng.random((K, K)) < density) * rng.integers(1, 10, (K, K))
    P = C / np.maximum(C.sum(axis=1, keepdims=True), 1)
    return P


def _logprob(P, path):
    return sum(np.log(P[i, j]) if P[i, j] > 0 else -np.inf for i, j in zip(path[:-1], path[1:]))


def test_viterbi_is_optimal_against_brute_force():
    rng = np.random.default_rng(0)
    checked = infeasible = 0
    for _ in range(25):
        K = 5
        P = _random_chain(K, rng)
        L = log_transitions(sp.csr_matrix(P))
        g = MaxProductGraph(L)
        for n in (1, 2, 3, 4, 5):
            a, b = (int(x) for x in rng.integers(0, K, 2))
            best = -np.inf
            if n == 1:
                best = 0.0 if a == b else -np.inf
            else:
                for mid in itertools.product(range(K), repeat=n - 2):
                    best = max(best, _logprob(P, (a, *mid, b)))
            if np.isfinite(best):
                path = viterbi_path(g, a, b, n)
                assert len(path) == n and path[0] == a and path[-1] == b
                assert _logprob(P, path) == pytest.approx(best, abs=1e-12)
                checked += 1
            else:
                with pytest.raises(NoPathError, match=f"exactly {n} frames"):
                    viterbi_path(L, a, b, n)
                infeasible += 1
    assert checked > 50 and infeasible > 5


def test_forward_scores_match_viterbi():
    rng = np.random.default_rng(1)
    P = _random_chain(8, rng, 0.5)
    g = MaxProductGraph(log_transitions(P))
    S = g.forward([0, 3], 6)
    for row, a in enumerate((0, 3)):
        scores, _ = g.viterbi(a, 6)
        np.testing.assert_allclose(S[row], scores)


def test_self_transitions_and_explicit_log_one_edges():
    # a deterministic cycle 0 -> 1 -> 2 -> 0 with P = 1: log P = 0 must still count as an edge
    P = sp.csr_matrix(np.roll(np.eye(3), 1, axis=1))
    path = viterbi_path(log_transitions(P), 0, 2, 6)
    np.testing.assert_array_equal(path, [0, 1, 2, 0, 1, 2])
    with pytest.raises(NoPathError, match="none of exactly 5 frames"):
        viterbi_path(log_transitions(P), 0, 2, 5)
    # with a self-loop on 1 any length >= 3 works
    P2 = sp.csr_matrix(np.array([[0, 1, 0], [0, 0.5, 0.5], [1.0, 0, 0]]))
    assert list(viterbi_path(log_transitions(P2), 0, 2, 5)) == [0, 1, 1, 1, 2]
    with pytest.raises(NoPathError, match="shortest path from state 0 to 2 takes 3 frames"):
        viterbi_path(log_transitions(P2), 0, 2, 2)
    P3 = sp.csr_matrix(np.array([[0.5, 0.5, 0], [0, 1.0, 0], [0, 0, 1.0]]))
    with pytest.raises(NoPathError, match="cannot be reached"):
        viterbi_path(log_transitions(P3), 1, 0, 4)


def test_viterbi_argument_errors():
    L = log_transitions(np.eye(3))
    with pytest.raises(ValueError, match="out of range"):
        viterbi_path(L, 0, 7, 3)
    with pytest.raises(ValueError, match="at least 1 frame"):
        viterbi_path(L, 0, 0, 0)
    with pytest.raises(ValueError, match="log-probabilities"):
        viterbi_path(sp.csr_matrix(np.eye(3) * 2.0), 0, 0, 2)


# ---------------------------------------------------------------- on the manifold
@pytest.fixture(scope="module")
def msynth(small_manifold):
    return ViterbiSynthesizer().fit(small_manifold)


def test_manifold_path_has_n_frames_hits_targets_and_uses_observed_transitions(small_manifold, msynth):
    m = small_manifold
    counts = m.states_.counts_.tocsr()
    g = MaxProductGraph(log_transitions(observed_transitions(m.states_)))
    u = m.corpus_.utterances[2]
    labels = m.states_.labels_
    a, b = int(labels[u.start + 5]), int(labels[u.start + 25])
    path = viterbi_path(g, a, b, 21)
    assert path.shape == (21,) and path[0] == a and path[-1] == b
    assert all(counts[i, j] > 0 for i, j in zip(path[:-1], path[1:]))
    # the observed state sequence of the same frames is a feasible path, so the optimum is at least as likely
    obs = labels[u.start + 5: u.start + 26]
    P = observed_transitions(m.states_)
    lp = lambda p: sum(np.log(P[i, j]) for i, j in zip(p[:-1], p[1:]))  # noqa: E731
    assert lp(path) >= lp(obs) - 1e-9


def test_manifold_synthesis_through_oracle_targets(small_manifold, msynth):
    m = small_manifold
    tg = targets_from_utterance(m, m.corpus_.utterances[3].id)
    tr = msynth.synthesize(tg)
    assert isinstance(tr, Trajectory) and isinstance(msynth, Synthesizer)
    assert tr.n_frames == m.corpus_.utterances[3].n_frames
    assert tr.Fx.shape == (tr.n_frames, m.Fx_.shape[1]) and tr.Fx.dtype == np.float32
    assert tr.Fy.shape == (tr.n_frames, 3)
    # at every target frame the path sits in the target's state
    np.testing.assert_array_equal(tr.states[tg.frames], [t.state for t in tg.targets])
    counts = m.states_.counts_.tocsr()
    moves = tr.states[tg.frames[0]: tg.frames[-1] + 1]
    assert all(counts[i, j] > 0 for i, j in zip(moves[:-1], moves[1:]))
    frames = tr.frames(m)
    assert frames.shape == (tr.n_frames, m.corpus_.frames.shape[1])


def test_no_path_error_names_the_gap(small_manifold, msynth):
    m = small_manifold
    fut = m.states_.future(0)
    far = int(np.flatnonzero(np.isfinite(fut) & (fut >= 3))[0])
    tg = targets_from_points(m, [(0, 0), (1, far)], n_frames=4)
    with pytest.raises(NoPathError, match=r"gap 0 .*frame 0.*frame 1.*2 frames"):
        msynth.synthesize(tg)
    loose = ViterbiSynthesizer(strict=False).fit(m).synthesize(tg)
    assert loose.warnings and "unreachable" in loose.warnings[0]
    assert loose.states[1] != far


def test_phone_targets_choose_states_from_the_phone_clusters(small_manifold, msynth):
    m = small_manifold
    tg = targets_from_phones(m, "sil 0.2 m 0.08 aa 0.12 p 0.08 iy 0.12 sil 0.2")
    tr = msynth.synthesize(tg)
    mids, labels, *_ = m.corpus_.phone_table()
    for f, lab in zip(tg.frames, tg.labels):
        cluster_states = set(m.states_.labels_[mids[labels == lab]].tolist())
        assert int(tr.states[f]) in cluster_states
    # the lattice choice is at least as probable as always taking each phone's most frequent state
    g = MaxProductGraph(log_transitions(observed_transitions(m.states_)))

    def score(states):
        s = 0.0
        for k in range(len(states) - 1):
            n = int(tg.frames[k + 1] - tg.frames[k] + 1)
            s += g.forward([states[k]], n)[0, states[k + 1]]
        table = {lab: msynth._candidates(lab) for lab in set(tg.labels)}
        for lab, st in zip(tg.labels, states):
            c, lp = table[lab]
            s += lp[list(c).index(st)]
        return s

    chosen = [int(tr.states[f]) for f in tg.frames]
    frequent = [int(msynth._candidates(lab)[0][0]) for lab in tg.labels]
    assert score(chosen) >= score(frequent) - 1e-9


def test_interpolation_passes_through_targets_and_holds_outside(small_manifold):
    m = small_manifold
    tg = targets_from_utterance(m, m.corpus_.utterances[1].id)
    X = np.array([t.x for t in tg.targets])
    for kind in ("linear", "cubic"):
        tr = make_synthesizer(kind, m).synthesize(tg)
        assert tr.method == kind and tr.Fy is None
        np.testing.assert_allclose(tr.Fx[tg.frames], X, rtol=1e-5, atol=1e-4)
        np.testing.assert_allclose(tr.Fx[: tg.frames[0]], np.repeat(X[:1], tg.frames[0], 0), atol=1e-4)
    lin = make_synthesizer("linear", m).synthesize(tg)
    f0, f1 = tg.frames[:2]
    mid = (f0 + f1) // 2
    w = (mid - f0) / (f1 - f0)
    np.testing.assert_allclose(lin.Fx[mid], (1 - w) * X[0] + w * X[1], rtol=1e-5, atol=1e-4)
    # phone-only targets use the phone's cluster mean
    ph = make_synthesizer("linear", m).synthesize(tg.phones_only())
    mids, labels, *_ = m.corpus_.phone_table()
    lab = tg.labels[1]
    np.testing.assert_allclose(ph.Fx[tg.frames[1]], m.Fx_[mids[labels == lab]].mean(0), rtol=1e-4, atol=1e-4)
    with pytest.raises(ValueError, match="unknown synthesis method 'spline'"):
        make_synthesizer("spline", m)


# ---------------------------------------------------------------- targets and bad input
def test_phone_string_parsing_and_errors():
    assert parse_phone_string("p 0.08 ax 0.05, t .1") == [("p", 0.08), ("ax", 0.05), ("t", 0.1)]
    with pytest.raises(TargetError, match="not label/duration pairs"):
        parse_phone_string("p 0.08 ax")
    with pytest.raises(TargetError, match=r"phone 1 \('ax'\): duration 'fast'"):
        parse_phone_string("p 0.08 ax fast")
    with pytest.raises(TargetError, match="empty phone string"):
        parse_phone_string("  ")


def test_target_construction_and_bad_inputs(small_manifold, tmp_path):
    m = small_manifold
    tg = targets_from_phones(m, [("p", 0.1), ("aa", 0.15), ("m", 0.1)])
    assert tg.n_frames == 21 and list(tg.frames) == [3, 10, 18] and tg.labels == ["p", "aa", "m"]
    # ARPAbet input meets the corpus's British set through normalisation
    arpa = targets_from_phones(m, "P 0.1 AA1 0.15 M 0.1")
    assert arpa.labels == ["p", "aa", "m"]
    with pytest.raises(UnknownPhoneError, match=r"'qx'.*known phones: .*\baa\b"):
        targets_from_phones(m, "p 0.1 qx 0.1")
    with pytest.raises(TargetError, match="same frame"):
        targets_from_phones(m, "p 0.1 t 0.004 aa 0.004")
    merged = targets_from_phones(m, "p 0.1 t 0.004 aa 0.004", on_collision="merge")
    assert len(merged.targets) == 2
    with pytest.raises(TargetError, match="no utterance 'nope'"):
        targets_from_utterance(m, "nope")
    uid = m.corpus_.utterances[0].id
    n = m.corpus_.utterances[0].n_frames
    with pytest.raises(TargetError, match=f"key frame {n + 3} is outside"):
        targets_from_utterance(m, uid, key_frames=[0, 5, n + 3])
    with pytest.raises(TargetError, match="state 99999 is outside"):
        targets_from_points(m, [(0, 1), (4, 99999)], n_frames=10)
    with pytest.raises(TargetError, match="frame 12 is outside"):
        targets_from_points(m, [(0, 1), (12, 2)], n_frames=10)
    dense = targets_from_utterance(m, uid, key_frames=range(0, n, 4))
    assert dense.has_oracle and len(dense.targets) == len(range(0, n, 4))


def test_targets_from_textgrid_and_text(small_manifold, tmp_path):
    m = small_manifold
    tgfile = tmp_path / "a.TextGrid"
    tgfile.write_text(
        'File type = "ooTextFile"\nObject class = "TextGrid"\n\nxmin = 0\nxmax = 0.4\ntiers? <exists>\nsize = 1\n'
        'item []:\n    item [1]:\n        class = "IntervalTier"\n        name = "phones"\n        xmin = 0\n'
        '        xmax = 0.4\n        intervals: size = 3\n        intervals [1]:\n            xmin = 0\n'
        '            xmax = 0.1\n            text = "sil"\n        intervals [2]:\n            xmin = 0.1\n'
        '            xmax = 0.25\n            text = "M"\n        intervals [3]:\n            xmin = 0.25\n'
        '            xmax = 0.4\n            text = "AA1"\n', encoding="utf-8")
    tg = targets_from_textgrid(m, tgfile)
    assert tg.labels == ["sil", "m", "aa"] and tg.n_frames == 24
    tx = targets_from_text(m, "map")
    assert tx.labels[0] == "sil" and tx.labels[1:4] == ["m", "ae", "p"]
    tr = ViterbiSynthesizer(strict=False).fit(m).synthesize(tx)
    assert tr.n_frames == tx.n_frames and np.isfinite(tr.Fx).all()


def test_synthesizers_reject_colliding_targets(small_manifold, msynth):
    bad = TargetSequence((Target(3, "p", 0), Target(3, "aa", 1)), (), 10, 60.0)
    with pytest.raises(ValueError, match="both at frame 3"):
        msynth.synthesize(bad)
    with pytest.raises(ValueError, match="both at frame 3"):
        make_synthesizer("linear", small_manifold).synthesize(bad)


def test_phones_missing_from_training_get_a_stand_in(small_manifold):
    from engine.phonetics.targets import stand_in_phone

    assert stand_in_phone("ng", ["t", "m", "n", "s"]) == "n"
    assert stand_in_phone("zh", ["s", "sh"]) == "sh"
    assert stand_in_phone("ua", ["aa", "ax", "ia"]) == "ia"
    assert stand_in_phone("qq", ["aa"]) is None
    # a held-out utterance may hold a phone its training corpus never saw: the synthesisers substitute and say so
    from engine.phonetics.phonesets import canonical_phones

    m = small_manifold
    known = {p.label for u in m.corpus_.utterances for p in u.phones}
    missing = [p for p in canonical_phones() if p not in known and stand_in_phone(p, sorted(known))]
    if not missing:
        pytest.skip("the small corpus holds every phone")
    label = missing[0]
    tg = TargetSequence((Target(2, "aa"), Target(9, label), Target(16, "m")), (), 20, 60.0)
    for method in ("linear", "viterbi"):
        tr = make_synthesizer(method, m).synthesize(tg)
        assert any(f"{label!r}" in w and "stands in" in w for w in tr.warnings)


def test_inverse_dims_maps_state_means_through_a_higher_dimensional_map(small_manifold):
    m = small_manifold
    tg = targets_from_utterance(m, m.corpus_.utterances[5].id)
    syn = ViterbiSynthesizer(inverse_dims=4).fit(m)
    tr = syn.synthesize(tg)
    base = ViterbiSynthesizer().fit(m).synthesize(tg)
    np.testing.assert_array_equal(tr.states, base.states)  # same path, mapped back differently
    lab = m.states_.labels_
    s = int(tr.states[tg.frames[1]])
    np.testing.assert_allclose(syn.points_[s], m.Fy_[lab == s, :4].mean(axis=0), rtol=1e-5, atol=1e-5)
    assert syn._inverse().n_dims == 4 and tr.Fx.shape == base.Fx.shape and np.isfinite(tr.Fx).all()
    k = m.Fy_.shape[1]
    with pytest.raises(ValueError, match=f"inverse_dims must be in 1..{k}"):
        ViterbiSynthesizer(inverse_dims=k + 1).fit(m)


def test_inverse_maps_beside_delaunay(small_manifold):
    """ViterbiSynthesizer(inverse=...): the same state path through the state means or the local-linear map."""
    from engine.phonetics.targets import targets_from_utterance
    from engine.synthesis.viterbi import ViterbiSynthesizer

    m = small_manifold
    u = m.corpus_.utterances[2]
    tg = targets_from_utterance(m, u.id)
    dela = ViterbiSynthesizer().fit(m).synthesize(tg)
    mean = ViterbiSynthesizer(inverse="state-mean").fit(m).synthesize(tg)
    np.testing.assert_array_equal(mean.states, dela.states)  # the inverse map never changes the path
    lab = m.states_.labels_
    expect = np.stack([m.Fx_[lab == k].mean(0) for k in mean.states])
    np.testing.assert_allclose(mean.Fx, expect, rtol=1e-4, atol=1e-4)
    smooth = ViterbiSynthesizer(inverse="state-mean", smoothing=2.0).fit(m).synthesize(tg)
    assert np.abs(np.diff(smooth.Fx, axis=0)).sum() < np.abs(np.diff(mean.Fx, axis=0)).sum()
    ll = ViterbiSynthesizer(inverse="local-linear", inverse_dims=5, n_neighbors=30).fit(m).synthesize(tg)
    assert ll.Fx.shape == dela.Fx.shape and np.isfinite(ll.Fx).all()
    # the 5-D local-linear map places the path's states nearer the real frames than 3-D Delaunay does
    truth = m.Fx_[u.start:u.stop]
    err = {k: float(np.sqrt(((t.Fx - truth) ** 2).sum(1).mean())) for k, t in (("delaunay", dela), ("ll5", ll))}
    assert err["ll5"] < err["delaunay"], err
    with pytest.raises(ValueError, match="inverse must be one of"):
        ViterbiSynthesizer(inverse="nearest").fit(m)
    with pytest.raises(ValueError, match="smoothing must be >= 0"):
        ViterbiSynthesizer(smoothing=-1).fit(m)


def test_stored_state_inverse_table_gives_the_delaunay_path_exactly(small_manifold, tmp_path):
    """The manifold file's state_x_ table replaces the tetrahedralisation in a new process."""
    from engine.manifold.model import Manifold
    from engine.phonetics.targets import targets_from_utterance
    from engine.synthesis.viterbi import ViterbiSynthesizer

    m = Manifold.load(small_manifold.save(tmp_path / "m.npz"))
    assert m.state_x_ is not None and m._inverse is None
    np.testing.assert_array_equal(m.state_x_, small_manifold.inverse_map.transform(small_manifold.states_.centroids_))
    u = m.corpus_.utterances[0]
    targets = targets_from_utterance(m, u.id, on_collision="merge")
    fast = ViterbiSynthesizer(strict=False).fit(m).synthesize(targets)
    assert m._inverse is None  # no Delaunay was built
    m.state_x_ = None  # a file without the table: made again from local triangulations, the same rows
    again = ViterbiSynthesizer(strict=False).fit(m).synthesize(targets)
    assert m._inverse is None and m.state_x_ is not None
    np.testing.assert_allclose(again.Fx, fast.Fx, rtol=0, atol=1e-5 * np.abs(fast.Fx).max())
