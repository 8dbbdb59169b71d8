"""The explorer on a manifold built from a corpus stored in blocks (its frames read from the blocks)."""
from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def blocked_manifold(tmp_path_factory, small_corpus):
    from app.files.source_loading import load_source
    from engine.manifold.model import Manifold
    from engine.recordings.corpus_blocks import save_blocked
    from engine.recordings.frame_blocks import BlockFrames

    corpus = small_corpus.subset([u.id for u in small_corpus.utterances if u.stop <= 1500])
    folder = tmp_path_factory.mktemp("blocked_window")
    src = folder / "c.npz"
    save_blocked(corpus, src, block_frames=512)
    from engine.recordings.corpus_blocks import load_blocked

    lazy = load_blocked(src)
    Manifold(n_states=30, random_state=0).fit(lazy).save(folder / "m.npz")
    m, _ = load_source(folder / "m.npz", prepare_views=True)
    assert isinstance(m.corpus_.frames, BlockFrames)  # the window works from the blocks, not a copy
    return m, corpus


def test_window_on_a_blocked_manifold_clicks_synthesises_and_plays(qapp, qtbot, blocked_manifold,
                                                                   main_window_factory):
    from tests.app.test_gui import _points

    m, corpus = blocked_manifold
    with main_window_factory(qapp, m) as win:
        s, ed = win.state, win.editor
        u = m.corpus_.utterances[1]
        s.select_frame(u.start + 3)
        qapp.processEvents()
        assert s.frame == u.start + 3 and s.state == int(m.states_.labels_[u.start + 3])
        np.testing.assert_allclose(win.lip_view.main.points, _points(m, corpus.frames[u.start + 3]), atol=1e-4)
        ed.set_source("utterance")
        ed.utt_box.setCurrentIndex(1)
        assert ed.load() and s.utterance == u.id
        ed.set_method("linear")
        ed.synthesize()
        qtbot.waitUntil(lambda: s.synthetic is not None, timeout=30000)
        assert "RMSE(X)" in ed.readout.text()
        s.set_playback(10)
        np.testing.assert_allclose(win.lip_view.main.points, _points(m, corpus.frames[u.start + 10]), atol=1e-4)
        s.set_playback(len(s.original) - 3)
        s.set_playing(True)
        qtbot.waitUntil(lambda: not s.playing, timeout=5000)
        assert s.playback == len(s.original) - 1


def test_file_open_fits_a_blocked_corpus_from_its_blocks_as_the_command_line_reads_it(qapp, qtbot, tmp_path,
                                                                                       small_corpus,
                                                                                       main_window_factory):
    """File › Open on a corpus stored in blocks reads it with the command line's reader: the frames stay
    in the block files (never gathered) and the window shows the manifold fitted on them."""
    from app.cli._common import load_corpus_arg
    from engine.recordings.corpus_blocks import save_blocked
    from engine.recordings.frame_blocks import BlockFrames

    corpus = small_corpus.subset([u.id for u in small_corpus.utterances if u.stop <= 1200])
    src = tmp_path / "blocked.npz"
    save_blocked(corpus, src, block_frames=400)
    cli = load_corpus_arg(src)
    assert isinstance(cli.frames, BlockFrames)
    with main_window_factory(qapp, None) as win:
        runner = win.open_source(str(src))  # what File › Open does with the chosen file
        qtbot.waitUntil(lambda: runner.state != "running", timeout=120000)
        assert runner.state == "done", getattr(win, "last_error_message", None)
        m = win.state.manifold
        assert m is not None and isinstance(m.corpus_.frames, BlockFrames)
        assert m.corpus_.frames.paths == cli.frames.paths and m.corpus_.n_frames == corpus.n_frames
        np.testing.assert_array_equal(m.corpus_.frames[:50], corpus.frames[:50])
        assert win.state.source["kind"] == "corpus"
