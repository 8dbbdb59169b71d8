import numpy as np
import pytest

from engine.recordings.corpus import Corpus, CorpusError, PhoneInterval, Utterance


def make(frames=None, utts=None, **kw):
    if frames is None:
        frames = np.random.default_rng(0).standard_normal((20, 6)).astype(np.float32)
    if utts is None:
        utts = [Utterance("a", 0, 10, ((0.0, 0.05, "p"), (0.05, 0.15, "aa"))), Utterance("b", 10, 20)]
    return Corpus(frames=frames, rate=60.0, utterances=utts, **kw)


def test_valid_corpus_properties():
    c = make()
    assert c.n_frames == 20 and c.n_points == 2 and c.bounds.tolist() == [[0, 10], [10, 20]]
    assert c.utterance_index.tolist() == [0] * 10 + [1] * 10
    mids, labels, utt, st, en = c.phone_table()
    assert labels.tolist() == ["p", "aa"]
    assert mids.tolist() == [2, 6]  # 0.025 s * 60 = 1.5 -> 2 ; 0.1 s -> 6
    assert isinstance(c.utterances[0].phones[0], PhoneInterval)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(frames=np.full((20, 6), np.nan)), "NaN/inf"),
        (dict(frames=np.ones((20, 5))), "multiple of dims"),
        (dict(utts=[Utterance("a", 0, 10), Utterance("b", 10, 10), Utterance("c", 10, 20)]), "is empty"),
        (dict(utts=[Utterance("a", 0, 10), Utterance("b", 11, 20)]), "starts at frame 11"),
        (dict(utts=[Utterance("a", 0, 10)]), "cover 10 frames"),
        (dict(utts=[Utterance("a", 0, 10, ((0.0, 0.5, "p"),)), Utterance("b", 10, 20)]), "outside the utterance"),
        (dict(utts=[Utterance("a", 0, 10, ((0.0, 0.1, "p"), (0.05, 0.12, "b"))), Utterance("b", 10, 20)]),
         "overlap"),
        (dict(utts=[Utterance("a", 0, 10, ((0.1, 0.05, "p"),)), Utterance("b", 10, 20)]), "not after start"),
        (dict(utts=[Utterance("a", 0, 10), Utterance("a", 10, 20)]), "appears twice"),
        (dict(faces=np.array([[0, 1, 5]])), "faces index"),
        (dict(point_names=["x"]), "point names"),
        (dict(latent={"jaw": np.zeros(3)}), "latent"),
    ],
)
def test_bad_corpora_raise(kwargs, message):
    with pytest.raises(CorpusError, match=message):
        make(**kwargs)


def test_nan_message_names_frame():
    F = np.zeros((20, 6), np.float32)
    F[7, 3] = np.inf
    with pytest.raises(CorpusError, match="frame 7 column 3"):
        make(frames=F)


def test_save_load_round_trip(tmp_path):
    c = make(faces=np.array([[0, 1, 0]]), point_names=["l", "r"], latent={"jaw": np.arange(20.0)})
    p = c.save(tmp_path / "c.npz")
    d = Corpus.load(p)
    np.testing.assert_array_equal(d.frames, c.frames)
    assert d.utterances == c.utterances and d.point_names == ["l", "r"] and d.rate == 60.0
    np.testing.assert_array_equal(d.latent["jaw"], c.latent["jaw"])
    assert [f.name for f in tmp_path.iterdir()] == ["c.npz"]  # no temp file left behind


def test_load_rejects_foreign_npz(tmp_path):
    np.savez(tmp_path / "x.npz", a=np.zeros(3))
    with pytest.raises(CorpusError, match="not a Lipspace corpus"):
        Corpus.load(tmp_path / "x.npz")


def test_subset_keeps_phones_and_reindexes():
    c = make()
    s = c.subset(["b"])
    assert s.n_frames == 10 and s.utterances[0].start == 0
    np.testing.assert_array_equal(s.frames, c.frames[10:])


def test_utterance_lookup_follows_changes_to_the_list():
    c = Corpus(frames=np.zeros((30, 6), np.float32), rate=60, dims=3,
               utterances=[Utterance("a", 0, 10), Utterance("b", 10, 20), Utterance("c", 20, 30)])
    assert c.utterance("b").start == 10 and c.utterance("c").stop == 30
    c.utterances[1] = Utterance("z", 10, 20)  # replaced in place: the same list, the same length
    assert c.utterance("z").start == 10
    with pytest.raises(KeyError, match="no utterance 'b'"):
        c.utterance("b")
    c.utterances = [Utterance("q", 0, 30)]  # a new list
    assert c.utterance("q").stop == 30
    with pytest.raises(KeyError, match="no utterance 'a'"):
        c.utterance("a")


def test_label_codes_are_numpy_unique():
    from engine.recordings.corpus import label_codes

    labels = ["sil", "aa", "b", "aa", "", "Z", "zh", "é", "b", "sil"]
    names, inv = label_codes(labels)
    ref_names, ref_inv = np.unique(np.asarray(labels, dtype=str), return_inverse=True)
    np.testing.assert_array_equal(names, ref_names)
    np.testing.assert_array_equal(inv, ref_inv.reshape(-1))
    names2, inv2 = label_codes(np.asarray(labels, dtype=str))
    np.testing.assert_array_equal(names2, ref_names)
    np.testing.assert_array_equal(inv2, inv)


def test_phone_table_is_kept_until_the_utterances_change():
    c = make(frames=np.zeros((100, 6), np.float32),
             utts=[Utterance("a", 0, 50, (PhoneInterval(0.0, 0.2, "p"), PhoneInterval(0.2, 0.5, "a"))),
                   Utterance("b", 50, 100, (PhoneInterval(0.1, 0.4, "m"),))])
    t1 = c.phone_table()
    assert c.phone_table() is t1  # built once
    assert not t1[0].flags.writeable  # readers cannot change what the next reader gets
    np.testing.assert_array_equal(t1[1], ["p", "a", "m"])
    c.utterances[1] = Utterance("b", 50, 100, (PhoneInterval(0.1, 0.4, "b"),))  # a new utterance object
    t2 = c.phone_table()
    assert t2 is not t1 and t2[1].tolist() == ["p", "a", "b"]


def test_a_faulty_phone_is_named_among_many_valid_ones():
    good = tuple(PhoneInterval(0.01 * k, 0.01 * k + 0.01, "a") for k in range(100))
    bad = good[:57] + (PhoneInterval(good[57].start, good[57].start, "a"),) + good[58:]  # zero length
    utts = [Utterance(f"u{i}", 60 * i, 60 * i + 60, good) for i in range(3)] + [Utterance("u3", 180, 240, bad)]
    with pytest.raises(CorpusError, match="utterance 'u3' phone 57 .*end is not after start"):
        make(frames=np.zeros((240, 6), np.float32), utts=utts)
