"""Registration (head motion, recording offsets), per-speaker normalisation, lip aperture and kinematic landmarks."""
import numpy as np
import pytest

from engine.io import concat
from engine.io.readers.matrix import corpus_from_matrix
from engine.recordings.corpus import Corpus, CorpusError, Utterance
from engine.recordings.kinematics import kinematic_landmarks, lip_aperture, with_kinematic_labels
from engine.recordings.layouts import read_layout
from engine.recordings.registration import normalise_speakers, register
from engine.talker.multispeaker import generate_recordings, layout_text


def _corpus(recs, layout, points=None):
    parts = []
    for r in recs:
        c = corpus_from_matrix(r.id + ".npy", r.matrix, layout, rate=r.rate, points=points)
        u = c.utterances[0]
        parts.append(Corpus(frames=c.frames, rate=c.rate, utterances=[Utterance(r.id, 0, u.stop, speaker=r.speaker)],
                            dims=3, point_names=c.point_names, point_roles=c.point_roles, name=r.id))
    return concat(parts)


@pytest.fixture(scope="module")
def with_reference(tmp_path_factory):
    f = tmp_path_factory.mktemp("lay") / "ref.layout"
    f.write_text(layout_text(reference=True))
    recs = generate_recordings(n_speakers=1, n_utterances=3, duration_s=(1.0, 1.0), head_motion=4.0,
                               reference=True, seed=1)
    return _corpus(recs, read_layout(f)), recs


def test_rigid_registration_removes_head_motion(with_reference):
    c, recs = with_reference
    ul = c.point_names.index("UL")
    before = c.frames[:, 3 * ul + 1].std()  # UL moves sideways only with the head
    r = register(c, method="auto")
    assert r.registration.startswith("rigid (Procrustes) to reference sensors NOSE, LMA, RMA")
    assert r.point_names == ["UL", "LL", "LC", "RC"] and r.point_roles[0] == "upper_lip"  # references dropped
    after = r.frames[:, 1].std()
    assert before > 1.0 and after < 0.25 * before
    # distances between points are kept exactly (a rigid motion per frame)
    np.testing.assert_allclose(lip_aperture(r), lip_aperture(c), rtol=1e-4)
    kept = register(c, method="rigid", drop_reference=False)
    ref = [i for i, role in enumerate(kept.point_roles) if role == "reference"]
    P = kept.frames.reshape(kept.n_frames, -1, 3)[:, ref]
    assert P.std(axis=0).max() < 0.1  # reference sensors no longer move (sensor noise 0.05)


def test_rigid_needs_three_reference_sensors(with_reference):
    c, _ = with_reference
    lips = c.subset([c.utterances[0].id])
    lips = Corpus(frames=lips.frames[:, :12], rate=lips.rate, utterances=lips.utterances,
                  point_names=lips.point_names[:4], point_roles=lips.point_roles[:4])
    with pytest.raises(CorpusError, match=r"at least 3 reference sensors.*method='utterance'"):
        register(lips, method="rigid")
    with pytest.raises(ValueError, match=r"expected one of auto, rigid"):
        register(lips, method="procrustes")


def test_utterance_centring_removes_offsets_between_recordings():
    recs = generate_recordings(n_speakers=1, n_utterances=6, duration_s=(1.0, 1.0), utterance_offset=6.0,
                               head_motion=0.0, seed=2)
    from engine.recordings.layouts import BUILTIN

    c = _corpus(recs, BUILTIN["ema7x6"])

    def between_share(corpus):
        F = corpus.frames.astype(np.float64)
        means = np.stack([F[u.start:u.stop].mean(0) for u in corpus.utterances])
        return float(means.var(0).sum() / F.var(0).sum())

    truth = _corpus(generate_recordings(n_speakers=1, n_utterances=6, duration_s=(1.0, 1.0), utterance_offset=0.0,
                                        head_motion=0.0, seed=2), BUILTIN["ema7x6"])  # same speech, no offsets
    assert between_share(c) > 0.5 > between_share(truth) + 0.1  # the fault: offsets between utterances dominate
    r = register(c, method="auto")
    assert r.registration.startswith("utterance centring")
    assert between_share(r) <= between_share(truth) + 0.01  # what is left differs in articulation, not position
    assert register(c.subset([recs[0].id]), method="auto") is not None  # one utterance: nothing to do


def test_speaker_normalisation_mean_and_scale():
    recs = generate_recordings(n_speakers=3, n_utterances=2, duration_s=(0.8, 0.8), seed=4)
    from engine.recordings.layouts import BUILTIN

    c = _corpus(recs, BUILTIN["ema7x6"])
    assert c.speakers == ["S1", "S2", "S3"]
    assert normalise_speakers(c, mode="none") is c
    n = normalise_speakers(c, mode="auto")
    spk = np.array([u.speaker for u in c.utterances])[c.utterance_index]
    means = [n.frames[spk == s].mean(0) for s in c.speakers]
    np.testing.assert_allclose(means[0], means[1], atol=1e-3)
    np.testing.assert_allclose(means[0], c.frames.mean(0), atol=1e-3)
    s = normalise_speakers(c, mode="mean+scale")
    rms = [np.sqrt(((s.frames[spk == k] - s.frames[spk == k].mean(0)) ** 2).mean()) for k in c.speakers]
    np.testing.assert_allclose(rms, rms[0], rtol=1e-3)
    assert "speaker normalisation mean+scale over 3 speakers" in s.history[-1]
    one = c.subset([recs[0].id])
    assert normalise_speakers(one) is one  # one speaker: auto does nothing


def test_kinematic_landmarks_and_labels():
    rate = 60.0
    t = np.arange(240) / rate
    ap = 5 + 4 * np.sin(2 * np.pi * 2.0 * t)  # maxima at t = 0.125 + k/2
    frames = np.zeros((240, 6), np.float32)
    frames[:, 2] = ap / 2
    frames[:, 5] = -ap / 2
    c = Corpus(frames=frames, rate=rate, utterances=[Utterance("u", 0, 240)], point_names=["UL", "LL"],
               point_roles=["upper_lip", "lower_lip"])
    np.testing.assert_allclose(lip_aperture(c), ap, rtol=1e-5)
    f, lab = kinematic_landmarks(c)
    opens = f[lab == "open"]
    np.testing.assert_allclose(opens / rate, 0.125 + 0.5 * np.arange(len(opens)), atol=1.5 / rate)
    assert set(lab) == {"open", "closed", "opening", "closing"}
    # order: open -> closing -> closed -> opening -> open ...
    k = int(np.flatnonzero(lab == "open")[0])
    assert list(lab[k:k + 5]) == ["open", "closing", "closed", "opening", "open"]
    kl = with_kinematic_labels(c)
    mids, labels = kl.phone_table()[:2]
    np.testing.assert_array_equal(mids, f)
    np.testing.assert_array_equal(labels, lab)


class _Graph:
    """A stand-in fitted state graph: ``labels_`` per frame, ``adjacency_``, ``scc_labels_``."""

    def __init__(self, labels, n_states, edges):
        import scipy.sparse as sp
        from scipy.sparse.csgraph import connected_components

        self.labels_ = np.asarray(labels)
        a, b = zip(*edges) if edges else ((), ())
        self.adjacency_ = sp.csr_matrix((np.ones(len(a), bool), (a, b)), shape=(n_states, n_states))
        self.scc_labels_ = connected_components(self.adjacency_, directed=True, connection="strong")[1]


def _two_speaker_corpus():
    F = np.zeros((40, 3), np.float32)
    utts = [Utterance(f"u{k}", 10 * k, 10 * k + 10, speaker="A" if k < 2 else "B") for k in range(4)]
    return Corpus(frames=F, rate=60, utterances=utts)


def test_explain_split_names_speakers_recordings_or_nothing():
    from engine.recordings.registration import explain_split

    c = _two_speaker_corpus()
    # states 0,1 for speaker A's frames, 2,3 for B's; no transitions between the pairs
    g = _Graph(np.repeat([0, 1, 2, 3], 10), 4, [(0, 1), (1, 0), (2, 3), (3, 2)])
    msg = explain_split(g, c)
    assert "along speakers" in msg and "speaker A" in msg and "speaker B" in msg and "--speaker-norm mean" in msg
    # one speaker: the same islands follow the recordings
    one = Corpus(frames=c.frames, rate=60, utterances=[Utterance(u.id, u.start, u.stop) for u in c.utterances])
    msg = explain_split(g, one)
    assert "along recordings" in msg and "2 utterances (u0, u1)" in msg and "--register utterance" in msg
    # a piece cut out of the middle of every utterance is neither
    lab = np.tile(np.r_[np.zeros(4, int), np.ones(2, int), np.zeros(4, int)], 4)
    g = _Graph(lab, 2, [(0, 1)])
    assert explain_split(g, one) is None
