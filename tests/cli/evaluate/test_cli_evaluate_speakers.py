"""`lipspace evaluate` on a real-style corpus of two speakers: speakers normalised by default as `build` does, a
warning when the held-out speakers never appear in training, and unreachable gaps reported with their cause."""
import contextlib
import io
from dataclasses import replace
from types import SimpleNamespace

import pytest

from app.cli import main


def _run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, out.getvalue(), err.getvalue()


def _two_speakers(register_as="utterance"):
    from engine.io import concat, resample
    from engine.io.readers.matrix import corpus_from_matrix
    from engine.recordings.corpus import Utterance
    from engine.recordings.layouts import BUILTIN
    from engine.recordings.registration import register
    from engine.talker.multispeaker import generate_recordings

    parts = []
    for r in generate_recordings(n_speakers=2, n_utterances=4, duration_s=(2.0, 2.5), seed=3):
        c = corpus_from_matrix(f"{r.id}.mat", r.matrix, BUILTIN["ema7x6"], rate=r.rate)
        parts.append(replace(c, utterances=[Utterance(r.id, 0, c.n_frames, speaker=r.speaker)], name=r.id))
    return resample(register(concat(parts, name="two"), method=register_as), 60)


@pytest.fixture(scope="module")
def two(tmp_path_factory):
    path = tmp_path_factory.mktemp("ev") / "two.npz"
    _two_speakers().save(path)
    return path


def test_speakers_are_normalised_by_default_and_disjoint_speakers_warned(two):
    test = "S2_U01,S2_U02,S2_U03,S2_U04"
    rc, out, err = _run(["evaluate", str(two), "--test-ids", test, "-q"])
    assert rc == 0, err
    assert "per-speaker normalisation: each speaker's mean frame removed (S1, S2; as 'lipspace build' does)" in out
    assert "warning: train and test speakers are disjoint: the held-out speaker(s) S2 (4 utterances) have no " \
           "training utterance; the manifold is trained on S1 only" in err
    rc, out_mean, _ = _run(["evaluate", str(two), "--test-ids", test, "-q", "--speaker-norm", "mean"])
    assert rc == 0
    assert out_mean.split("protocol 'states'")[1] == out.split("protocol 'states'")[1]  # the default is 'mean'
    rc, out_none, err_none = _run(["evaluate", str(two), "--test-ids", test, "-q", "--speaker-norm", "none"])
    assert rc == 0 and "no per-speaker normalisation (--speaker-norm none) over 2 speakers" in out_none
    assert "errors mostly measure the offset between the speakers' lips" in err_none
    # gaps that cannot reach their target are reported with their cause, in the table and as a warning
    for o, e in ((out, err), (out_none, err_none)):
        assert "gap(s) could not reach their target state in time" in o
        assert "unreachable gaps: likely cause:" in o and "held-out speaker(s) S2 never appear in training" in o
        assert "gap(s) could not reach their target state in time (they end at the nearest reachable state); " \
               "likely cause:" in e


def test_a_within_speaker_split_is_not_warned_about(two):
    rc, out, err = _run(["evaluate", str(two), "--test-ids", "S1_U02,S2_U03", "-q"])
    assert rc == 0 and "disjoint" not in err and "no training utterance" not in err


def test_islands_of_the_training_graph_are_named_as_the_cause():
    import warnings

    from app.cli.evaluate import gap_cause
    from engine.manifold.model import Manifold

    corpus = _two_speakers(register_as="none")  # speakers 100 mm apart, nothing removed
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = Manifold(n_states=20, speaker_normalisation="none").fit(corpus)
    cause = gap_cause(SimpleNamespace(manifold=m, state_warnings=[], n_states=20), corpus, {})
    assert cause.startswith("likely cause: the training state graph (20 states) splits into 2 islands")
    assert "along speakers" in cause


def test_spreads_can_be_equalised_too(two):
    """`--speaker-norm mean+scale` is what `build --speaker-norm mean+scale` does: the run differs from `mean`, names
    the mode, and the warning about unseen speakers says the spreads were equalised."""
    import numpy as np

    from app.cli.evaluate import normalise_per_speaker
    from engine.recordings.corpus import Corpus

    test = "S2_U01,S2_U02,S2_U03,S2_U04"
    rc, out, err = _run(["evaluate", str(two), "--test-ids", test, "-q", "--speaker-norm", "mean+scale"])
    assert rc == 0, err
    assert ("per-speaker normalisation: each speaker's mean frame removed and its spread scaled to the pooled spread "
            "(S1, S2; --speaker-norm mean+scale)") in out
    assert "per-speaker normalisation removes each speaker's mean frame and equalises their spreads" in err
    rc, out_mean, _ = _run(["evaluate", str(two), "--test-ids", test, "-q", "--speaker-norm", "mean"])
    assert rc == 0 and out_mean.split("protocol 'states'")[1] != out.split("protocol 'states'")[1]
    corpus = Corpus.load(two)
    scaled = normalise_per_speaker(corpus, mode="mean+scale")
    spk = np.array([u.speaker for u in corpus.utterances])[corpus.utterance_index]
    rms = [np.sqrt(((scaled.frames[spk == k] - scaled.frames[spk == k].mean(0)) ** 2).mean()) for k in ("S1", "S2")]
    np.testing.assert_allclose(rms[0], rms[1], rtol=1e-3)
    with pytest.raises(ValueError, match="expected 'mean' or 'mean\\+scale'"):
        normalise_per_speaker(corpus, mode="scale")
