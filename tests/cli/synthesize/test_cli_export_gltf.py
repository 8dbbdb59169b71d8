"""``lipspace synthesize -o speech.glb``: the glTF animation plays the same frames as ``-o frames.npy``."""
import wave

import numpy as np
import pytest

from app.cli import main
from engine.io.writers.gltf import read_gltf_morph

PHONES = "sil 0.1 b 0.08 iy 0.12 m 0.08 sil 0.1"


@pytest.fixture(scope="module")
def mfile(small_manifold, tmp_path_factory):
    return small_manifold.save(tmp_path_factory.mktemp("gltf") / "m.npz")


def _tone(path, seconds=0.5, rate=16000):
    t = np.arange(int(seconds * rate)) / rate
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes((np.sin(2 * np.pi * 180 * t) * 9000).astype(np.int16).tobytes())
    return path


def test_glb_plays_the_synthesised_frames_with_the_audio_beside(mfile, small_manifold, tmp_path, capsys):
    npy, glb = tmp_path / "frames.npy", tmp_path / "speech.glb"
    tone = _tone(tmp_path / "voice.wav")
    assert main(["synthesize", "--manifold", str(mfile), "--phones", PHONES, "-o", str(npy)]) == 0
    assert main(["synthesize", "--manifold", str(mfile), "--phones", PHONES, "--audio", str(tone),
                 "-o", str(glb)]) == 0
    assert "morph targets" in capsys.readouterr().out
    frames = np.load(npy)
    r = read_gltf_morph(glb)
    played = r["base"][None] + np.einsum("nk,kvd->nvd", r["weights"], r["targets"])
    n, m = frames.shape[0], small_manifold.shape_.n_components_
    assert played.shape == (n, small_manifold.corpus_.n_points, 3)
    assert r["targets"].shape[0] == 2 * m  # X_k+ and X_k-
    tol = 8 * np.finfo(np.float32).eps * float(np.abs(frames).max()) * np.sqrt(m)
    np.testing.assert_allclose(played.reshape(n, -1), frames, rtol=0, atol=tol)
    np.testing.assert_allclose(r["times"], np.arange(n) / small_manifold.corpus_.rate, rtol=1e-6)
    np.testing.assert_array_equal(r["faces"], small_manifold.corpus_.faces)
    assert r["scale"] == pytest.approx(0.001) and r["extras"]["audio"] == "speech.wav"
    assert (tmp_path / "speech.wav").read_bytes() == tone.read_bytes()
    assert sorted(q.name for q in tmp_path.iterdir()) == ["frames.npy", "speech.glb", "speech.wav", "voice.wav"]


def test_glb_errors_are_one_line_and_write_nothing(mfile, tmp_path, capsys):
    glb = tmp_path / "a.glb"
    assert main(["synthesize", "--manifold", str(mfile), "--phones", PHONES, "--values", "fx", "-o", str(glb)]) == 2
    assert "a glTF animation always holds the lip frames" in capsys.readouterr().err
    assert main(["synthesize", "--manifold", str(mfile), "--phones", PHONES, "--audio", str(tmp_path / "none.wav"),
                 "-o", str(glb)]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["synthesize", "--manifold", str(mfile), "--phones", PHONES, "--gltf-scale", "0",
                 "-o", str(glb)]) == 2
    assert "--gltf-scale 0: must be above 0" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())
