"""An articulograph corpus whose axes are permuted, flipped and mirrored against the views (data x = down,
y = the talker's right, z = forward): the lip view, fig2c, the MP4 and the glTF export show the lips from the front
(upper lip above lower lip, the talker's left corner on the viewer's right), and `info` says how."""
from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest

#: generator (x anterior, y left, z up) -> the lab's axes: x = down, y = right, z = forward (left-handed)
LAB_AXES = np.array([[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])


@pytest.fixture(scope="module")
def lab_manifold(make_articulograph_manifold):
    return make_articulograph_manifold(n_speakers=1, n_utterances=3, duration_s=(1.5, 1.5), seed=21, n_states=12,
                                       axes=LAB_AXES, name="lab")


def _index(m, name):
    return m.corpus_.point_names.index(name)


def _check_front(m, P):
    """P: the four sensors (UL, LL, LC, RC order of the corpus) in view coordinates (x right, y up)."""
    ul, ll, lc, rc = (P[_index(m, n)] for n in ("UL", "LL", "LC", "RC"))
    assert ul[1] > ll[1] and lc[0] > rc[0]
    assert lc[0] - rc[0] > 2 * abs(lc[1] - rc[1])  # corners left and right, not top and bottom


def test_info_states_the_orientation(lab_manifold, tmp_path):
    from app.cli import main

    path = tmp_path / "lab.npz"
    lab_manifold.corpus_.save(path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["info", str(path)]) == 0
    line = next(ln for ln in out.getvalue().splitlines() if ln.startswith("orientation"))
    assert line.startswith("orientation x = down, y = right, z = forward (from the roles: upper lip above lower lip")
    assert "mirrored (left-handed)" in line


def test_fig2c_draws_the_front_view(lab_manifold):
    from app.figures import make_fig2c

    fig = make_fig2c(lab_manifold)
    assert fig.lipspace["view"] == (0, 1)
    for P in fig.lipspace["shapes"]:
        _check_front(lab_manifold, P)


def test_gltf_is_in_gltf_axes(lab_manifold, tmp_path):
    from app.export.animation import export_animation
    from engine.io.writers.gltf import read_gltf_morph

    path = tmp_path / "lips.glb"
    export_animation(lab_manifold, lab_manifold.Fx_[:20], path, rate=60.0)
    g = read_gltf_morph(path)
    base = np.asarray(g["base"], np.float64) / 0.001  # metres -> mm
    _check_front(lab_manifold, base)
    ul, lc = base[_index(lab_manifold, "UL")], base[_index(lab_manifold, "LC")]
    assert ul[2] > lc[2]  # glTF +Z is the model's front: the lips ahead of the corners
    assert "mirrored" in g["extras"]["orientation"]


@pytest.mark.gui
def test_lip_view_shows_the_corners_left_and_right_on_screen(qapp, lab_manifold):
    from app.models.state import AppState
    from app.scene.projection import project, view_transform
    from app.views.lip_view import LipView

    view = LipView(AppState(lab_manifold))
    view.resize(480, 360)
    view.show()
    for _ in range(5):
        qapp.processEvents()
    try:
        M, size = view_transform(view.plotter)
        xy, _ = project(np.asarray(view.main.points, np.float64), M, size)  # the sensors on the screen
        _check_front(lab_manifold, xy)
    finally:
        view.close_view()
        view.deleteLater()
        qapp.processEvents()


@pytest.mark.gui
def test_the_mp4_shows_a_wide_mouth(qapp, lab_manifold, tmp_path):
    import av

    from app.export.current import export_current_animation
    from app.models.state import AppState

    s = AppState(lab_manifold)
    s.set_utterance(lab_manifold.corpus_.utterances[0].id)
    path = tmp_path / "lips.mp4"
    export_current_animation(s, path, size=(320, 240))
    with av.open(str(path)) as f:
        img = next(f.decode(video=0)).to_ndarray(format="rgb24").astype(int)
    img = img[:, : img.shape[1] // 2]  # the lip panel (the manifold panel beside it)
    lips = (img[..., 0] > 150) & (img[..., 1] < 120) & (img[..., 2] < 120)  # the red contour tube
    ys, xs = np.nonzero(lips)
    assert xs.size > 100
    assert np.ptp(xs) > 2.0 * np.ptp(ys)  # a wide mouth, not one standing on a corner
