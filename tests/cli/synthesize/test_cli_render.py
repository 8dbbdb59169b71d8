"""``lipspace render``: decode the MP4 and check frame count, rate, duration and the audio stream."""
import wave
from fractions import Fraction

import numpy as np
import pytest

from app.cli import main

av = pytest.importorskip("av")

pytestmark = pytest.mark.gui  # VTK renders off-screen into an X server (Xvfb under the test run)

PHONES = "sil 0.1 m 0.08 aa 0.12 p 0.08 sil 0.1"  # 0.48 s -> 29 frames at 60 Hz
SIZE = "96x64"


@pytest.fixture(scope="module")
def mfile(small_manifold, tmp_path_factory):
    return small_manifold.save(tmp_path_factory.mktemp("render") / "m.npz")


def _tone(path, seconds, rate=16000):
    t = np.arange(int(seconds * rate)) / rate
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes((np.sin(2 * np.pi * 220 * t) * 8000).astype(np.int16).tobytes())
    return path


def _decode(path):
    with av.open(str(path)) as f:
        v = f.streams.video[0]
        info = {"rate": v.average_rate, "width": v.codec_context.width, "height": v.codec_context.height,
                "audio": [s.codec_context.name for s in f.streams.audio],
                "duration": float(f.duration) / av.time_base if f.duration else None}
        frames = [fr.to_ndarray(format="rgb24") for fr in f.decode(video=0)]
    info["frames"] = frames
    return info


def test_render_with_audio_decodes_to_the_right_frames_rate_and_duration(mfile, tmp_path, capsys):
    out = tmp_path / "talk.mp4"
    wav = _tone(tmp_path / "voice.wav", 1.0)  # longer than the video: cut to its length
    assert main(["render", "--manifold", str(mfile), "--phones", PHONES, "--audio", str(wav), "--size", SIZE,
                 "-q", "-o", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    info = _decode(out)
    n = len(info["frames"])
    assert n == 29 and info["rate"] == Fraction(60)
    assert (info["width"], info["height"]) == (96, 64)
    assert info["audio"] == ["aac"]
    assert info["duration"] == pytest.approx(n / 60, abs=0.05)
    # the lips move: the frames are not all the same picture
    diffs = [np.abs(f.astype(int) - info["frames"][0]).mean() for f in info["frames"]]
    assert max(diffs) > 0.5
    assert sorted(q.name for q in tmp_path.iterdir()) == ["talk.mp4", "voice.wav"]  # no temporary left


def test_side_by_side_with_manifold_panel_and_the_original(mfile, small_manifold, tmp_path):
    from app.export.video import render_video

    m = small_manifold
    c, u = m.corpus_, m.corpus_.utterances[0]
    out = tmp_path / "panel.mp4"
    assert main(["render", "--manifold", str(mfile), "--phones", PHONES, "--trajectory", "--size", SIZE, "-q",
                 "-o", str(out)]) == 0
    info = _decode(out)
    assert (info["width"], info["height"]) == (192, 64) and info["audio"] == [] and len(info["frames"]) == 29
    # the original (24 frames) beside a shorter synthesis (18 frames, holds its last frame), both paths drawn
    orig = slice(u.start, u.start + 24)
    synth = m.shape_.inverse_transform(m.Fx_[u.start:u.start + 18] * 0.5)
    p = render_video(tmp_path / "both.mp4", synth, rate=c.rate, faces=c.faces, original=c.frames[orig],
                     Y=m.Fy_[u.start:u.start + 18], Y_original=m.Fy_[orig], cloud=m.Fy_, size=(96, 64))
    info = _decode(p)
    assert (info["width"], info["height"]) == (192, 64) and len(info["frames"]) == 24
    with pytest.raises(ValueError, match=r"Y must be \(18, >=3\)"):
        render_video(tmp_path / "bad.mp4", synth, rate=c.rate, Y=m.Fy_[:5], size=(96, 64))
    assert not (tmp_path / "bad.mp4").exists()


def test_render_errors_and_interrupt_leave_no_file(mfile, tmp_path, capsys, monkeypatch):
    out = tmp_path / "x.mp4"
    assert main(["render", "--manifold", str(mfile), "--phones", PHONES, "-o", str(tmp_path / "x.avi")]) == 2
    assert "must end in .mp4" in capsys.readouterr().err
    assert main(["render", "--manifold", str(mfile), "--phones", PHONES, "--side-by-side", "-o", str(out)]) == 2
    assert "give --utterance" in capsys.readouterr().err

    import app.export.video as video

    real = video._Scene.draw
    calls = []

    def interrupted(self, *a):
        calls.append(1)
        if len(calls) == 5:
            raise KeyboardInterrupt
        return real(self, *a)

    monkeypatch.setattr(video._Scene, "draw", interrupted)
    out.write_bytes(b"old video")
    assert main(["render", "--manifold", str(mfile), "--phones", PHONES, "--size", SIZE, "-q", "-o", str(out),
                 "--force"]) == 130
    assert "nothing was written" in capsys.readouterr().err
    assert out.read_bytes() == b"old video" and sorted(q.name for q in tmp_path.iterdir()) == ["x.mp4"]


def test_real_sigint_mid_render_leaves_no_half_video(mfile, tmp_path):
    """A real SIGINT once the temporary video exists: exit 130, one line, the old file intact."""
    import os
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "talk.mp4"
    out.write_bytes(b"old video")
    proc = subprocess.Popen([sys.executable, "-m", "app.cli", "render", "--manifold", str(mfile), "--phones",
                             "sil 10 aa 10 sil 10", "--size", SIZE, "-o", str(out), "--force"],  # 30 s: still rendering
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=dict(os.environ))
    deadline = time.monotonic() + 60
    while not list(tmp_path.glob(".*talk*.part*.mp4")) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err[-2000:]
    assert "nothing was written" in err and "Traceback" not in err, err[-2000:]
    assert out.read_bytes() == b"old video" and sorted(q.name for q in tmp_path.iterdir()) == ["talk.mp4"]
