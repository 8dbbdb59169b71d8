"""File › Export animation on the explorer's (Qt-free) state: glTF of the current trajectory, MP4 beside."""
import numpy as np
import pytest

from app.export.current import export_current_animation
from app.models.state import AppState, TrajectoryData
from engine.io.writers.gltf import read_gltf_morph


def _synthetic(m, start, n, label="manifold"):
    # a short trajectory through real rows of F^y / F^x, scaled so it differs from the original
    return TrajectoryData(Y=m.Fy_[start:start + n], Fx=m.Fx_[start:start + n] * 0.8, label=label, rate=m.corpus_.rate)


def test_glb_of_the_current_trajectory_prefers_the_synthetic(app_manifold, tmp_path):
    m = app_manifold
    s = AppState(m)
    with pytest.raises(ValueError, match="no trajectory to export"):
        export_current_animation(s, tmp_path / "a.glb")
    u = m.corpus_.utterances[1]
    s.set_utterance(u.id)
    files = export_current_animation(s, tmp_path / "orig.glb")
    r = read_gltf_morph(files[0])
    Fx = m.Fx_[u.start:u.stop]
    np.testing.assert_allclose(r["Fx"], Fx, rtol=1e-6, atol=1e-6 * float(np.abs(Fx).max()))
    assert r["extras"]["source"] == u.id and files == [tmp_path / "orig.glb"]  # the synthetic talker has no audio
    s.set_trajectories(synthetic=_synthetic(m, u.start, 12))
    r = read_gltf_morph(export_current_animation(s, tmp_path / "syn.gltf")[0])
    assert r["Fx"].shape == (12, m.shape_.n_components_) and r["extras"]["source"] == "manifold"
    np.testing.assert_allclose(r["Fx"], m.Fx_[u.start:u.start + 12] * 0.8, rtol=1e-5, atol=1e-4)
    with pytest.raises(ValueError, match=r"\.glb, \.gltf or \.mp4"):
        export_current_animation(s, tmp_path / "a.avi")


@pytest.mark.gui
def test_mp4_of_a_synthetic_trajectory(app_manifold, tmp_path):
    av = pytest.importorskip("av")
    m = app_manifold
    s = AppState(m)
    s.set_trajectories(synthetic=_synthetic(m, 100, 15))
    seen = []
    p = export_current_animation(s, tmp_path / "talk.mp4", size=(64, 48),
                                 progress=lambda st, d, t: seen.append((st, d, t)))[0]
    with av.open(str(p)) as f:
        v = f.streams.video[0]
        assert (v.codec_context.width, v.codec_context.height) == (128, 48)  # lips + manifold panel
        assert sum(1 for _ in f.decode(video=0)) == 15 and not f.streams.audio
    assert seen[-1] == ("render", 15, 15)
