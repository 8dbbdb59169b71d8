"""Sound everywhere there is sound, in the window: typed text speaks and its MP4 carries it, a Haskins file
opened directly shows and plays its AUDIO with its word tier, and a machine that cannot play says so once
(needs a display: Xvfb is started if absent)."""
from __future__ import annotations

import shutil
import wave

import pytest

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def win(qapp, app_manifold, main_window_factory):
    with main_window_factory(qapp, app_manifold) as w:
        yield w


def _seconds(path) -> float:
    with wave.open(str(path), "rb") as w:
        return w.getnframes() / w.getframerate()


@pytest.mark.skipif(shutil.which("espeak-ng") is None, reason="espeak-ng is not installed")
def test_typed_text_speaks_and_its_mp4_carries_the_sound(win, qtbot, tmp_path):
    import av

    from app.export.current import export_current_animation
    from app.files.sound import playback_audio, sound_dir

    s, ed = win.state, win.editor
    ed.set_method("linear")
    assert ed.set_text("bob meets mum", source="text")
    assert [w.label for w in ed.timeline.words] == ["bob", "meets", "mum"]      # the word tier of typed text
    ed.synthesize()
    qtbot.waitUntil(lambda: s.synthetic is not None, timeout=60000)
    wav = s.synthetic.extra["audio"]
    assert str(sound_dir()) in wav and "with the text spoken" in ed.readout.text()
    assert _seconds(wav) == pytest.approx(ed.targets.n_frames / ed.targets.rate, abs=0.05)  # on its times
    path, rate = playback_audio(s)                                               # what Play plays
    assert str(path) == wav and rate == ed.targets.rate
    out = export_current_animation(s, tmp_path / "bob.mp4", size=(160, 120))[0]  # File › Export animation
    with av.open(str(out)) as f:
        audio = [st for st in f.streams if st.type == "audio"]
        assert len(audio) == 1 and float(f.duration / 1e6) == pytest.approx(_seconds(wav), abs=0.15)


def test_a_machine_that_cannot_play_says_so_once(win, qtbot, tmp_path, monkeypatch):
    import numpy as np

    from app.models.state import TrajectoryData
    from engine.files.atomic import write_wav_atomic

    s, audio = win.state, win.lip_view.audio
    if audio.available:
        pytest.skip("this machine has a sound device")
    wav = write_wav_atomic(tmp_path / "x.wav", np.zeros(16000), 16000)
    s.set_trajectories(original=None, synthetic=TrajectoryData(Y=np.zeros((30, 3), np.float32), rate=60.0,
                                                               extra={"audio": str(wav)}))
    win.statusBar().clearMessage()
    s.set_playing(True)
    msg = win.statusBar().currentMessage()
    assert msg.startswith("no sound: ") and audio.reason in msg
    s.set_playing(False)
    win.statusBar().clearMessage()
    s.set_playing(True)                                                          # said once, not at every Play
    assert win.statusBar().currentMessage() == ""
    s.set_playing(False)
    s.set_trajectories(synthetic=None)


def test_a_haskins_file_opened_in_the_window_shows_its_sound_and_words(win, qtbot, tmp_path, make_haskins_file):
    from app.files.sound import sound_dir

    path = make_haskins_file(tmp_path / "F01_B01_S02_R01_N.mat", seconds=3.0)
    runner = win.open_source(str(path))                                          # File › Open
    qtbot.waitUntil(lambda: runner.state != "running", timeout=180000)
    assert runner.state == "done", runner.error
    s, ed = win.state, win.editor
    u = s.manifold.corpus_.utterances[0]
    assert u.audio and u.audio.startswith(str(sound_dir()))                      # the AUDIO entry, in the cache
    ed.set_source("utterance")
    assert ed.load()
    assert [w.label for w in ed.timeline.words] == ["sp", "BOB", "MEETS", "MUM", "sp"]
    qtbot.waitUntil(lambda: ed.sound.shown_at is not None, timeout=30000)        # waveform and spectrogram
    assert ed.sound.isVisibleTo(ed) and ed.sound.display.duration == pytest.approx(3.0, abs=0.02)
    assert ed.sound.display.sample_rate == 44100


def test_the_rendering_dialog_closes_after_the_video_is_written_and_says_the_time_left(win, qtbot, tmp_path,
                                                                                         monkeypatch):
    import numpy as np
    from PySide6 import QtWidgets

    from app.models.state import TrajectoryData

    s = win.state
    s.set_utterance(s.manifold.corpus_.utterances[0].id)
    s.set_trajectories(synthetic=TrajectoryData(Y=np.asarray(s.original.Y)[:40], Fx=np.asarray(s.original.Fx)[:40],
                                                rate=s.original.rate, label="cut"))
    out = tmp_path / "v.mp4"
    monkeypatch.setattr(QtWidgets.QFileDialog, "getSaveFileName", lambda *a, **k: (str(out), "MP4 video (*.mp4)"))
    labels = []
    real = QtWidgets.QProgressDialog.setLabelText
    monkeypatch.setattr(QtWidgets.QProgressDialog, "setLabelText", lambda d, t: (labels.append(t), real(d, t))[1])
    win.export_animation_dialog()                                           # File › Export animation
    assert out.is_file() and win.statusBar().currentMessage() == f"wrote {out}"
    visible = lambda: [d for d in win.findChildren(QtWidgets.QProgressDialog) if d.isVisible()]  # noqa: E731
    assert visible() == []
    qtbot.wait(4500)                                                        # past Qt's show-after-4-s timer
    assert visible() == []
    assert any("left" in t for t in labels), labels[-3:]                   # the time left, as it rendered
    s.set_trajectories(synthetic=None)
    s.set_utterance(None)
