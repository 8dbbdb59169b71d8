"""The MP4 renderer's fast path: moving the lip mesh draws what the lip view's update draws."""
import numpy as np
import pytest


@pytest.mark.gui
def test_fast_move_gives_vtks_normals(app_manifold):
    """The renderer's per-frame move of a smooth lip mesh leaves VTK's normals filter's normals."""
    import pyvista as pv

    from app.export.video import _mover
    from app.scene.lips import add_lips

    c = app_manifold.corpus_
    F = np.asarray(c.faces, np.int64)
    pl = pv.Plotter(off_screen=True, window_size=(96, 64))
    try:
        h = add_lips(pl, c.points(0), F, offset=(5.0, 0.0, 0.0))
        move = _mover(h, F)
        assert move != h.update  # the fast path is the one taken
        before = np.asarray(h.mesh.point_data["Normals"]).copy()
        move(c.points(57))
        ours = np.asarray(h.mesh.point_data["Normals"]).copy()
        ref = pv.PolyData(h.mesh.points.copy(), h.mesh.faces.copy())
        ref.compute_normals(cell_normals=False, split_vertices=False, inplace=True)
    finally:
        pl.close()
    assert np.abs(ours - before).max() > 0.05  # the frame moved the normals
    angle = np.degrees(np.arccos(np.clip((ours * np.asarray(ref.point_data["Normals"])).sum(1), -1, 1)))
    assert angle.max() < 0.1


@pytest.mark.gui
def test_fast_move_draws_the_same_pictures_as_update(app_manifold):
    import app.export.video as video

    c = app_manifold.corpus_
    F = video._frames3(c.frames[300:306], c.dims, "frames")
    pictures = {}
    for how in ("fast", "update"):
        s = video._Scene(F, F[::-1].copy(), c.faces, None, None, None, (96, 64), None)
        try:
            if how == "update":
                s.move_main, s.move_second = s.main.update, s.second.update
            pictures[how] = [s.draw(F[k], F[-1 - k], None, "x").astype(int) for k in range(len(F))]
        finally:
            s.close()
    assert np.abs(pictures["fast"][0] - pictures["fast"][3]).mean() > 0.5  # the lips move
    for a, b in zip(pictures["fast"], pictures["update"]):
        assert np.abs(a - b).max() <= 1
