"""Live mirror (issue 14 item 4) and the lip mesh of video corpora (item 3).

A 24-frame video of the astronaut photo under known head motion stands in for a camera;
the manifold is built from the same video's import, so the live projection of its
frames must land where the build put them.
"""
from __future__ import annotations

import time

import numpy as np
import pytest

pytest.importorskip("mediapipe", reason="the [video] extra is not installed (pip install -e '.[video]')")
skdata = pytest.importorskip("skimage.data", reason="scikit-image (the [video] extra) is not installed")

from app.cli.explore import run_live  # noqa: E402
from app.models.live import LatestFrame, LiveProjector, LiveSession, check_video_manifold  # noqa: E402
from engine.io.video.clips import read_video, track_video  # noqa: E402
from engine.io.video.synth import default_motion, moving_image_frames, write_video  # noqa: E402

RATE = 30
N = 24


@pytest.fixture(scope="module")
def video_world(tmp_path_factory):
    from engine.manifold.model import Manifold

    d = tmp_path_factory.mktemp("live")
    img = np.ascontiguousarray(skdata.astronaut()[0:256, 96:352])
    write_video(d / "talk.mp4", moving_image_frames(img, default_motion(N, rate=RATE)), RATE)
    lm, found = track_video(d / "talk.mp4")
    assert found.all()
    corpus = read_video(d / "talk.mp4", landmarks=(lm, found))  # tracked once
    m = Manifold(n_states=4, n_neighbors=5, n_embedding=3).fit(corpus)
    m.save(d / "m.npz")
    return {"dir": d, "corpus": corpus, "manifold": Manifold.load(d / "m.npz"), "landmarks": lm}


def test_live_projection_lands_on_the_built_manifold(video_world):
    m, lm = video_world["manifold"], video_world["landmarks"]
    p = LiveProjector(m, rate=RATE, calibration_frames=N)
    assert all(p.push(lm[k], k) is None for k in range(N))  # learning the head template
    assert p.calibrating == 0
    out = [p.push(lm[k], k) for k in range(N)]
    Y = np.stack([s.y for s in out])
    # frame 0 has no previous live frame (velocity 0); every later one is the build's own F^y
    np.testing.assert_allclose(Y[1:], m.Fy_[1:N], atol=1e-3 * np.abs(m.Fy_).max())
    assert [s.state for s in out[1:]] == m.states_.predict(m.Fy_[1:N, :m.states_.centroids_.shape[1]]).tolist()
    # a 60 Hz stream whose every other frame was dropped gives the same velocities
    q = LiveProjector(m, rate=2 * RATE, calibration_frames=N)
    for k in range(N):
        q.push(lm[k], 2 * k)
    Y2 = np.stack([q.push(lm[k], 2 * k).y for k in range(N)])
    np.testing.assert_allclose(Y2[1:], Y[1:], atol=1e-5 * np.abs(Y).max())
    # a frame without a face restarts the velocity instead of inventing one
    assert q.push(None, 100) is None
    assert np.isfinite(q.push(lm[3], 101).y).all()
    hops = p.future(out[-1].state)
    assert hops[out[-1].state] == 0 and hops.shape == (m.states_.centroids_.shape[0],)


def test_latest_frame_counts_drops():
    box = LatestFrame()
    for k in range(3):
        box.put(k)
    assert box.take(0.1) == 2 and box.dropped == 2
    assert box.take(0.01) is None
    box.close()
    assert box.take(None) is None


class SlowTracker:
    """The real tracker, but 60 ms per frame: slower than a 30 fps stream."""

    def __init__(self):
        from engine.io.video.facemesh import FaceTracker

        self.t = FaceTracker()

    def track(self, rgb):
        time.sleep(0.06)
        return self.t.track(rgb)

    def close(self):
        self.t.close()


def _run(session, timeout=30.0):
    session.start()
    t0 = time.perf_counter()
    samples = []
    while time.perf_counter() - t0 < timeout:
        got, stats = session.poll()
        samples += got
        if stats.finished:
            break
        time.sleep(0.02)
    got, stats = session.poll()
    session.stop()
    return samples + got, stats


def test_session_keeps_up_or_drops_and_says_so(video_world):
    m, video = video_world["manifold"], video_world["dir"] / "talk.mp4"
    samples, stats = _run(LiveSession(m, str(video), calibration_frames=4, tracker_factory=SlowTracker))
    assert stats.received == N and stats.finished and not stats.error
    assert stats.dropped > 0 and stats.processed + stats.dropped == N
    assert f"dropped {stats.dropped}" in stats.line()
    assert all(np.isfinite(s.y).all() for s in samples) and len(samples) == stats.processed - 4


def test_wrong_manifold_and_missing_inputs_are_one_line_errors(video_world, small_manifold, tmp_path):
    from app.cli import CliError

    with pytest.raises(ValueError, match="the live mirror needs a manifold built from a video import"):
        check_video_manifold(small_manifold)
    with pytest.raises(ValueError, match="--interocular-mm"):
        LiveProjector(video_world["manifold"], rate=30, interocular_mm=300)
    with pytest.raises(CliError, match="--camera needs --manifold"):
        run_live(None, "0")
    with pytest.raises(CliError, match="no camera number and no such video file"):
        run_live(video_world["dir"] / "m.npz", str(tmp_path / "nothing.mp4"))


def test_video_corpus_lip_view_draws_the_facemesh_lip_surface(video_world):
    import pyvista as pv

    from app.scene import add_lips

    c = video_world["manifold"].corpus_
    assert c.faces is not None and c.faces.shape == (120, 3)  # kept through build, save and load
    P = c.frames.reshape(c.n_frames, -1, 3)
    pl = pv.Plotter(off_screen=True)
    try:
        h = add_lips(pl, P[0], c.faces, names=c.point_names)
        assert h.mesh.n_cells == 120 and "Normals" in h.mesh.point_data  # a shaded surface, not markers
        # front faces look at the camera (+z), as the lips do
        n = np.asarray(h.mesh.compute_normals(cell_normals=True, point_normals=False).cell_data["Normals"])
        assert (n[:, 2] > 0).mean() > 0.9
        h.update(P[5])
        np.testing.assert_allclose(h.points, P[5], atol=1e-4)
    finally:
        pl.close()


@pytest.mark.gui
def test_live_window_draws_trail_future_and_counts(video_world, qtbot):
    from app.views.live_view import LiveWindow

    session = LiveSession(video_world["manifold"], str(video_world["dir"] / "talk.mp4"), calibration_frames=4)
    session.start()
    win = LiveWindow(session)
    qtbot.addWidget(win)
    win.show()
    qtbot.waitUntil(lambda: win.last_stats is not None and win.last_stats.finished, timeout=30000)
    win.poll()
    assert len(win.scene.Y) > 0 and win.scene.marker.visible
    assert np.isfinite(win.scene.states.values).any()  # the current state's future hemisphere is coloured
    assert "dropped" in win.status.text() and "fps processed" in win.status.text()
    win.close()


@pytest.mark.gui
def test_explorer_lip_view_shows_the_lip_surface_of_a_video_corpus(qapp, video_world, main_window_factory):
    from app.scene.lips import LipsHandle

    m = video_world["manifold"]
    with main_window_factory(qapp, m, size=(1100, 800)) as w:
        lv = w.lip_view
        assert isinstance(lv.main, LipsHandle) and lv.main.mesh.n_cells  # the FaceMesh surface, not sensors
        assert lv.main.mesh.n_cells == 120 and "Normals" in lv.main.mesh.point_data
        w.state.select_frame(10)  # a click on frame 10
        for _ in range(5):
            qapp.processEvents()
        P = m.corpus_.frames.reshape(m.corpus_.n_frames, -1, 3)
        np.testing.assert_allclose(lv.main.points, P[10], atol=1e-4)  # it moves with the frames
