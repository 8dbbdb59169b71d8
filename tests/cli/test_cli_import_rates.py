"""Inputs at different frame rates join at one analysis rate, each resampled before joining, and the terminal
shows what the user needs: no internal API names, no native library logs, the roles summarised."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from app.cli import main
from engine.recordings.corpus import Corpus

REPO = Path(__file__).resolve().parents[2]
CLIPS = REPO.parent / "shared" / "data" / "talking-faces"


def _mat(path, rate, seed):
    import scipy.io

    from engine.talker.multispeaker import generate_recordings

    r = generate_recordings(n_speakers=1, n_utterances=1, duration_s=(1.0, 1.0), rate=rate, seed=seed)[0]
    scipy.io.savemat(path, {"data": r.matrix, "fs": np.array([[rate]])})
    return r.matrix.shape[0]


def test_recordings_at_different_rates_join_at_the_analysis_rate(tmp_path, capsys):
    n = [_mat(tmp_path / "ABCFIA01.mat", 250.0, 1), _mat(tmp_path / "ABCFIA02.mat", 200.0, 2)]
    out = tmp_path / "c.npz"
    files = [str(tmp_path / "ABCFIA01.mat"), str(tmp_path / "ABCFIA02.mat")]
    assert main(["import", *files, "--layout", "ema7x6", "-q", "--jobs", "1", "-o", str(out)]) == 0
    c = Corpus.load(out)
    assert c.rate == 60 and [u.n_frames for u in c.utterances] == [int(np.ceil(n[0] * 60 / 250)),
                                                                     int(np.ceil(n[1] * 60 / 200))]
    err = capsys.readouterr().err
    assert "resampled 250 -> 60 Hz" in err and "resampled 200 -> 60 Hz" in err
    assert main(["import", *files, "--layout", "ema7x6", "-q", "--jobs", "1", "--resample", "native",
                 "-o", str(tmp_path / "d.npz")]) == 2
    err = capsys.readouterr().err
    assert "different frame rates: 250 Hz (1 input, e.g. ABCFIA01), 200 Hz (1 input, e.g. ABCFIA02)" in err
    assert "--resample 60" in err and "engine." not in err


def test_no_message_names_an_internal_api(tmp_path, capsys):
    from engine.io import concat, read_matrix

    _mat(tmp_path / "a.mat", 250.0, 1)
    _mat(tmp_path / "b.mat", 200.0, 2)
    with pytest.raises(ValueError) as err:
        concat([read_matrix(tmp_path / "a.mat", layout="ema7x6"), read_matrix(tmp_path / "b.mat", layout="ema7x6")])
    assert "engine." not in str(err.value) and "--resample" in str(err.value)
    from engine.io import read_corpus, write_est_track

    t = np.arange(50) / 250.0
    ema = write_est_track(tmp_path / "c.ema", t, np.zeros((50, 4)), ["ul_x", "ul_y", "ll_x", "ll_y"])
    with pytest.raises(ValueError) as err:
        read_corpus(ema, rate=100.0)  # the file says 250 Hz
    assert "250 Hz but a rate of 100 Hz was given (--rate)" in str(err.value) and "engine." not in str(err.value)


needs_clips = pytest.mark.skipif(not CLIPS.is_dir(), reason=f"the real clips are not at {CLIPS}")


def _clip_folder(tmp_path, names):
    d = tmp_path / "videos"
    d.mkdir()
    for n in names:
        os.symlink(CLIPS / n, d / n)
    return d


def _lipspace(*argv):
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    env.pop("LIPSPACE_NATIVE_LOGS", None)
    return subprocess.run([sys.executable, "-c", "import sys; from app.cli import main; sys.exit(main())", *argv],
                          capture_output=True, text=True, env=env, cwd=REPO, timeout=600)


@needs_clips
def test_five_clips_at_22_25_and_30_fps_import_at_60_hz_with_a_clean_terminal(tmp_path):
    pytest.importorskip("mediapipe", reason="the [video] extra is not installed (pip install -e '.[video]')")
    from engine.io.video.clips import video_info

    names = [f"face{k}.mp4" for k in range(1, 6)]
    folder = _clip_folder(tmp_path, names)
    durations = [video_info(folder / n)[1] / video_info(folder / n)[0] for n in names]
    assert len({round(video_info(folder / n)[0], 3) for n in names}) == 3  # 22.13, 25 and 30 fps
    out = tmp_path / "all.npz"
    r = _lipspace("import", str(folder), "--resample", "60", "-o", str(out), "-q")
    assert r.returncode == 0, r.stderr
    c = Corpus.load(out)
    assert c.rate == 60 and [u.id for u in c.utterances] == [n[:-4] for n in names]
    # each clip keeps its duration (the face is found in every frame of these clips)
    assert np.allclose([u.n_frames / 60 for u in c.utterances], durations, atol=2 / 22.1)
    err = r.stderr
    for noise in ("TensorFlow Lite", "absl", "W0000", "inference_feedback_manager", "engine."):
        assert noise not in err, err
    roles = next(ln for ln in err.splitlines() if ln.startswith("lipspace import: roles"))
    assert roles == ("lipspace import: roles 80 points: upper_lip outer_0, inner_13; lower_lip outer_17, inner_14; "
                     "left_corner outer_291; right_corner outer_61; lip 74 points")
    assert max(len(ln) for ln in err.splitlines()) < 400
    assert {ln.split(" (")[0] for ln in err.splitlines() if "resampled" in ln} == {
        "lipspace import: resampled 22.1311 -> 60 Hz", "lipspace import: resampled 25 -> 60 Hz",
        "lipspace import: resampled 30 -> 60 Hz"}


@needs_clips
def test_clips_at_different_rates_are_refused_at_their_own_rate_before_tracking(tmp_path):
    folder = _clip_folder(tmp_path, ["face1.mp4", "face4.mp4"])
    r = _lipspace("import", str(folder), "--resample", "native", "-o", str(tmp_path / "x.npz"), "-q")
    assert r.returncode == 2
    assert "the videos have different frame rates (face1.mp4 22.13 Hz, face4.mp4 30 Hz)" in r.stderr
    assert "--resample 60" in r.stderr and "engine." not in r.stderr and "TensorFlow" not in r.stderr


@needs_clips
def test_clips_at_different_rates_default_to_the_analysis_rate(tmp_path):
    pytest.importorskip("mediapipe", reason="the [video] extra is not installed (pip install -e '.[video]')")
    folder = _clip_folder(tmp_path, ["face1.mp4", "face2.mp4"])
    out = tmp_path / "two.npz"
    r = _lipspace("import", str(folder), "-o", str(out), "-q")
    assert r.returncode == 0, r.stderr
    c = Corpus.load(out)
    assert c.rate == 60  # every input is analysed at 60 Hz: each clip resampled before they are joined
    assert sum(h.startswith("resampled") and "-> 60 Hz" in h for h in c.history) >= 2, c.history
