"""Exports of a real recording: MOCHA-TIMIT fsew0_001 (three 2-D sensors, no faces, its own WAV)."""
import numpy as np
import pytest


@pytest.fixture(scope="module")
def mocha(mocha_manifold):
    return mocha_manifold


def test_glb_of_markers_is_a_point_cloud_with_the_recording_beside(mocha, tmp_path):
    from app.export.animation import export_animation, utterance_audio
    from engine.io.writers.gltf import read_gltf_morph

    m = mocha
    u = m.corpus_.utterances[0]
    audio, why = utterance_audio(m, u.id)
    assert audio is not None, why
    from engine.files.staging import OutputExistsError

    (tmp_path / "fsew.wav").write_bytes(b"the user's own recording")  # beside a new animation: never replaced
    with pytest.raises(OutputExistsError, match="fsew.wav .the audio beside it. already exists"):
        export_animation(m, m.Fx_[u.start:u.stop], tmp_path / "fsew.glb", rate=m.corpus_.rate, audio=audio)
    assert (tmp_path / "fsew.wav").read_bytes() == b"the user's own recording"
    assert not (tmp_path / "fsew.glb").exists()
    (tmp_path / "fsew.wav").unlink()
    files = export_animation(m, m.Fx_[u.start:u.stop], tmp_path / "fsew.glb", rate=m.corpus_.rate, audio=audio)
    assert files == [tmp_path / "fsew.glb", tmp_path / "fsew.wav"]
    assert (tmp_path / "fsew.wav").read_bytes() == audio.read_bytes()
    again = export_animation(m, m.Fx_[u.start:u.stop], tmp_path / "fsew.glb", rate=m.corpus_.rate, audio=audio)
    assert again == files  # the save dialog confirmed replacing the animation: its own WAV goes with it
    r = read_gltf_morph(files[0])
    assert r["faces"] is None and r["base"].shape == (m.corpus_.n_points, 3)
    played = r["base"][None] + np.einsum("nk,kvd->nvd", r["weights"], r["targets"])
    from engine.recordings.orientation import anatomical_frame

    frame = anatomical_frame(m.corpus_, m.shape_.mean_)  # written in the talker's frame: x forward, y up
    assert frame.source == "roles"
    expect = frame.view(m.shape_.inverse_transform(m.Fx_[u.start:u.stop]).reshape(u.n_frames, -1, 2))
    np.testing.assert_allclose(played[..., :2], expect, rtol=0, atol=1e-4 * float(np.abs(expect).max()))
    np.testing.assert_array_equal(played[..., 2], 0.0)


@pytest.mark.gui
def test_mp4_carries_the_recording_cut_to_the_video(mocha, tmp_path):
    import av

    from app.export.animation import utterance_audio
    from app.export.video import render_video

    m = mocha
    c, u = m.corpus_, m.corpus_.utterances[0]
    audio, _ = utterance_audio(m, u.id)
    n = 30  # half a second of the 1.9-s utterance
    p = render_video(tmp_path / "fsew.mp4", c.frames[u.start:u.start + n], rate=c.rate, dims=c.dims, audio=audio,
                     size=(64, 48))
    with av.open(str(p)) as f:
        a = f.streams.audio[0]
        assert a.codec_context.name == "aac" and sum(1 for _ in f.decode(video=0)) == n
    with av.open(str(p)) as f:
        samples = sum(fr.samples for fr in f.decode(audio=0))
    # AAC pads to whole 1024-sample frames and adds its priming delay: within two frames of 0.5 s
    assert abs(samples / a.codec_context.sample_rate - n / c.rate) < 2 * 1024 / a.codec_context.sample_rate + 0.01


@pytest.mark.gui
def test_mp4_draws_sparse_lip_markers_as_the_lip_view_does(shared_data, tmp_path):
    """Haskins sensors (UL, LL, a corner, jaw): the video shows the sensors as the lip view does (spheres,
    straight lines, the aperture with its value), framed whole."""
    import av

    from app.export.video import _Scene, render_video
    from app.models.lip_drawing import drawing_of
    from app.scene import SensorsHandle, pick_display_point
    from engine.io import read_corpus

    c = read_corpus(shared_data / "haskins-ieee" / "F01_B01_S01_R01_N.mat")
    F = c.frames[:20]
    sensors = {"roles": c.point_roles, "names": c.point_names}
    from engine.recordings.corpus import frame_points

    pts = frame_points(np.asarray(F, np.float32), c.dims)
    d = drawing_of(pts.mean(axis=0), dims=3, roles=c.point_roles, names=c.point_names)
    s = _Scene(pts, None, None, None, None, None, (64, 48), d)
    try:
        assert isinstance(s.main, SensorsHandle) and s.main.segments is not None  # sensors, no contour
        assert s.main.label_texts[-1].endswith(" mm")  # the aperture's value
        s.plotter.render()
        w, h = s.plotter.window_size
        for frame in pts:  # every frame's sensors inside the picture
            for xyz in frame:
                x, y = pick_display_point(s.plotter, xyz)
                assert 0 <= x <= w and 0 <= y <= h, (x, y)
    finally:
        s.close()
    p = render_video(tmp_path / "h.mp4", F, rate=c.rate, dims=c.dims, size=(64, 48), **sensors)
    with av.open(str(p)) as f:
        assert sum(1 for _ in f.decode(video=0)) == 20
