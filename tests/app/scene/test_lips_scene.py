"""The lip mesh as drawn: smooth shading over point normals that follow the moving surface,
vermilion and skin colours."""
from __future__ import annotations

import numpy as np
import pytest

pv = pytest.importorskip("pyvista")

from app.scene.lips import SKIN, add_lips, lip_colours  # noqa: E402
from engine.talker.lipmodel import CONTROL_NAMES, LipModel  # noqa: E402


@pytest.fixture(scope="module")
def lip():
    return LipModel("default")


def _frame(lip, **kw):
    c = np.zeros((1, len(CONTROL_NAMES)))
    for k, v in kw.items():
        c[0, CONTROL_NAMES.index(k)] = v
    return lip.deform(c).reshape(-1, 3)


def test_mesh_is_smooth_shaded_with_vermilion_and_skin_colours(lip):
    pl = pv.Plotter(off_screen=True, window_size=(320, 240))
    try:
        h = add_lips(pl, _frame(lip, jaw=0.5), lip.faces, color=(0.8, 0.3, 0.3), names=lip.point_names)
        prop = h.actor.GetProperty()
        assert prop.GetInterpolation() != 0  # 0 = VTK_FLAT: facets
        assert "Normals" in h.mesh.point_data
        rgb = np.asarray(h.mesh.point_data["lip_rgb"])
        C = lip.cols
        inner, outer = rgb[:C].astype(int), rgb[(lip.rows - 1) * C:lip.rows * C].astype(int)
        assert (inner == np.round(255 * np.array([0.8, 0.3, 0.3]))).all()   # vermilion in the given colour
        assert (outer[:, 1] > inner[:, 1] + 60).all()                         # skin: lighter, towards SKIN
        # the normals follow the moving surface
        n0 = np.asarray(h.mesh.point_data["Normals"]).copy()
        h.update(_frame(lip, jaw=1.0, protrude=1.0))
        assert np.abs(np.asarray(h.mesh.point_data["Normals"]) - n0).max() > 0.05
    finally:
        pl.close()
    assert lip_colours(3, "red", ["a", "b", "c"]) is None  # other corpora keep one colour
    assert len(SKIN) == 3


def test_mouth_interior_shows_through_the_aperture_and_follows_the_handle(lip):
    pl = pv.Plotter(off_screen=True, window_size=(320, 240))
    try:
        pl.set_background("white")
        h = add_lips(pl, _frame(lip, jaw=0.8), lip.faces, color=(0.8, 0.3, 0.3), names=lip.point_names)
        assert len(h.extras) == 1
        pl.view_xy()
        pl.reset_camera()
        img = np.asarray(pl.screenshot(return_img=True))[..., :3].astype(int)
        # the centre of the open mouth, projected to the screen, is the dark interior, not the background
        up, lo = lip.midline
        P = _frame(lip, jaw=0.8)
        from app.scene import pick_display_point

        x, y = pick_display_point(pl, 0.5 * (P[up] + P[lo]))
        px = img[img.shape[0] - 1 - int(round(y)), int(round(x))]
        assert px.max() < 90, px
        h.set_visible(False)
        assert not any(a.GetVisibility() for a in (h.actor, *h.extras))
        h.remove()
        assert not pl.renderer.HasViewProp(h.extras[0])
    finally:
        pl.close()
    # other corpora's meshes get no interior
    pl = pv.Plotter(off_screen=True, window_size=(160, 120))
    try:
        assert add_lips(pl, _frame(lip), lip.faces).extras == ()
    finally:
        pl.close()
