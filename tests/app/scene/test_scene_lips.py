"""Sparse lip markers in the lip view: a labelled contour tube on any pyvista plotter."""
from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui
pv = pytest.importorskip("pyvista")

P = np.array([[10.0, 0.0, 6.0], [8.0, 0.0, -8.0], [-2.0, 25.0, -1.0], [-5.0, 0.0, -30.0]])


@pytest.fixture
def plotter():
    p = pv.Plotter(off_screen=True, window_size=(240, 200))
    yield p
    p.close()


def test_markers_with_roles_draw_a_labelled_contour(plotter):
    from app.scene import ContourHandle, add_lips

    h = add_lips(plotter, P, None, roles=["upper_lip", "lower_lip", "left_corner", "jaw"],
                 names=["UL", "LL", "ML", "JAW"], offset=(1.0, 0, 0))
    assert isinstance(h, ContourHandle)
    assert h.mesh.n_cells == len(h.contour.faces_) and h.mesh.n_points == 48 * 8
    assert h.markers.n_points == 4 and h.labels is not None
    np.testing.assert_allclose(h.points, P, atol=1e-5)
    before = np.array(h.mesh.points)
    h.update(P + [0, 0, 2.0])
    np.testing.assert_allclose(np.array(h.mesh.points) - before, [[0, 0, 2.0]] * h.mesh.n_points, atol=1e-4)
    np.testing.assert_allclose(h.points, P + [0, 0, 2.0], atol=1e-5)
    h.set_visible(False)
    assert not h.visible and not h.marker_actor.GetVisibility()
    plotter.render()
    with pytest.raises(ValueError, match="3 points, the lip markers are 4"):
        h.update(P[:3])


def test_contour_tube_normals_follow_the_frame_as_vtks_normals_filter(plotter):
    from app.scene import add_lips

    roles, names = ["upper_lip", "lower_lip", "left_corner", "jaw"], ["UL", "LL", "ML", "JAW"]
    h = add_lips(plotter, P, None, roles=roles, names=names, offset=(1.0, 0, 0))
    first = np.asarray(h.mesh.point_data["Normals"]).copy()
    for Q in (P + [0, 0, 2.0], P * [1.0, 0.4, 1.3], P + [[0, 3.0, 0], [0, -4.0, 2.0], [5.0, 0, 0], [0, 0, 0]]):
        h.update(Q)
        ours = np.asarray(h.mesh.point_data["Normals"]).copy()
        ref = pv.PolyData(np.array(h.mesh.points), np.array(h.mesh.faces))
        ref.compute_normals(cell_normals=False, split_vertices=False, inplace=True)
        np.testing.assert_allclose(ours, np.asarray(ref.point_data["Normals"]), atol=1e-4)
    assert np.abs(ours - first).max() > 0.1  # the last frame's shape turned the normals


def test_points_without_lip_roles_stay_spheres(plotter):
    from app.scene import ContourHandle, add_lips

    h = add_lips(plotter, P, None, roles=["jaw", "jaw", "tongue", "tongue"], names=["a", "b", "c", "d"])
    assert not isinstance(h, ContourHandle) and h.mesh.n_points == 4 and h.mesh.n_cells == 4
