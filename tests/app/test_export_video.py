"""The MP4 renderer's fast path: moving the lip mesh draws what the lip view's update draws."""
import numpy as np
import pytest


def test_vertex_normals_match_vtk(app_manifold):
    from app.export.video import _vertex_normals
    from app.scene.lips import lip_mesh

    c = app_manifold.corpus_
    P = c.points(57).astype(np.float32)
    F = np.asarray(c.faces, np.int64)
    mesh = lip_mesh(P, F)
    mesh.compute_normals(cell_normals=False, split_vertices=False, inplace=True)
    n = _vertex_normals(P, F, np.concatenate([F[:, 0], F[:, 1], F[:, 2]]))
    angle = np.degrees(np.arccos(np.clip((n * np.asarray(mesh.point_data["Normals"])).sum(1), -1, 1)))
    assert angle.max() < 0.1


@pytest.mark.gui
def test_fast_move_draws_the_same_pictures_as_update(app_manifold):
    import app.export.video as video

    c = app_manifold.corpus_
    F = video._frames3(c.frames[300:306], c.dims, "frames")
    pictures = {}
    for how in ("fast", "update"):
        s = video._Scene(F, F[::-1].copy(), c.faces, None, None, None, (96, 64), {"roles": None, "names": None})
        try:
            if how == "update":
                s.move_main, s.move_second = s.main.update, s.second.update
            pictures[how] = [s.draw(F[k], F[-1 - k], None, "x").astype(int) for k in range(len(F))]
        finally:
            s.close()
    assert np.abs(pictures["fast"][0] - pictures["fast"][3]).mean() > 0.5  # the lips move
    for a, b in zip(pictures["fast"], pictures["update"]):
        assert np.abs(a - b).max() <= 1
