"""Scene-building functions on an off-screen pyvista plotter."""
from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui

pv = pytest.importorskip("pyvista")


@pytest.fixture
def plotter():
    p = pv.Plotter(off_screen=True, window_size=(240, 200))
    p.set_background("white")
    yield p
    p.close()


def _red(plotter):
    plotter.render()  # screenshot() reuses the last frame unless told to render
    img = plotter.screenshot()
    return int(((img[..., 0] > 200) & (img[..., 1] < 60) & (img[..., 2] < 60)).sum())


def test_points_recolour_in_place(plotter):
    from app.scene import add_manifold_points

    rng = np.random.default_rng(0)
    Y = rng.normal(size=(300, 3))
    h = add_manifold_points(plotter, Y, rgb=np.tile([0.0, 0.0, 1.0], (300, 1)))
    plotter.reset_camera()
    assert _red(plotter) == 0
    actor = h.actor
    values = np.where(np.arange(300) < 150, 0.0, np.nan)
    h.set_colors(np.tile([1.0, 0.0, 0.0], (300, 1)), values)
    assert h.actor is actor and plotter.actors["manifold_points"] is actor  # same actor, no re-add
    assert _red(plotter) > 100
    assert np.isnan(h.values[150:]).all() and (h.values[:150] == 0).all()
    assert (h.rgb == [255, 0, 0]).all()
    with pytest.raises(ValueError, match="shape"):
        h.set_colors(np.zeros((3, 3)))


def test_click_picker_reports_point_under_the_cursor(plotter):
    from app.scene import add_manifold_points, enable_click_picking, pick_display_point

    rng = np.random.default_rng(1)
    Y = rng.uniform(-1, 1, size=(200, 3))
    h = add_manifold_points(plotter, Y, point_size=8)
    plotter.add_mesh(pv.Sphere(radius=0.05, center=(5, 5, 5)))  # not pickable through the picker list
    plotter.reset_camera()
    plotter.render()
    got = []
    picker = enable_click_picking(plotter, h.actor, lambda pid, xyz, shift: got.append((pid, xyz, shift)))
    # the point nearest the camera is never hidden behind another
    depth = np.linalg.norm(Y - np.array(plotter.camera.position), axis=1)
    i = int(np.argmin(depth))
    x, y = pick_display_point(plotter, Y[i])
    assert picker.pick(x, y, shift=True) == i
    assert got[0][0] == i and got[0][2] is True
    np.testing.assert_allclose(got[0][1], Y[i], atol=1e-5)
    assert picker.pick(2, 2) is None  # empty corner: nothing picked, no callback
    assert len(got) == 1
    picker.remove()


def test_trajectory_plane_axes_frame_path(plotter):
    from app import scene

    rng = np.random.default_rng(2)
    Y = np.cumsum(rng.normal(size=(60, 3)), axis=0)
    red = scene.add_trajectory(plotter, Y, scene.SYNTHETIC_COLOUR, name="syn")
    plotter.reset_camera()
    assert _red(plotter) > 50
    red.update(None)  # hidden when empty
    assert not red.visible and _red(plotter) == 0
    red.update(Y[:10])
    assert red.visible and red.mesh.n_points == 10
    plane = scene.add_zero_velocity_plane(plotter, [0, 0, 0], [0, 0, 2], 5)
    np.testing.assert_allclose(plane.mesh.point_normals.mean(0), [0, 0, 1], atol=1e-6)
    axes = scene.add_global_axes(plotter, [0, 0, 0], [1, 0, 0], [0, 0, 1], 2.0)
    assert axes["S"].mesh.bounds[1] == pytest.approx(2.0, rel=1e-3)
    local = scene.add_local_frame(plotter, length=1.0)
    assert not local.visible
    arrows = {k: (h.actor, h.mesh) for k, h in local.parts.items()}
    local.update([1, 1, 1], [0, 1, 0], [1, 0, 0], [0, 0, 1])
    assert local.visible and local.bounds("s")[3] == pytest.approx(2.0, rel=1e-3)  # from y=1, length 1 along +y
    assert local.bounds("v")[1] == pytest.approx(2.0, rel=1e-3) and local.bounds("normal")[5] == pytest.approx(
        2.0, rel=1e-3)
    local.update([0, 0, 0], [0, -3, 0], [0, 0, 0], [0, 0, 1])  # moved in place; a zero direction is hidden
    assert local.bounds("s")[2] == pytest.approx(-1.0, rel=1e-3) and not local.parts["v"].visible
    assert all(local.parts[k].actor is a and local.parts[k].mesh is m for k, (a, m) in arrows.items())
    marker = scene.add_marker(plotter, None, 0.1)
    actor = marker.actor
    marker.move([3, 4, 5])
    assert marker.visible and marker.actor is actor
    np.testing.assert_allclose(np.reshape(actor.GetBounds(), (3, 2)).mean(1), [3, 4, 5], atol=1e-3)
    C = rng.normal(size=(20, 3))
    path = scene.add_state_path(plotter, C, [3, 7, 9], node_radius=0.05)
    assert path.visible and np.array_equal(path.points, C[[3, 7, 9]])
    with pytest.raises(ValueError, match="normal"):
        scene.add_zero_velocity_plane(plotter, [0, 0, 0], [0, 0, 0], 1)


def test_ellipsoid_and_lips(plotter):
    from app import scene

    s = pv.Sphere(radius=1.0)
    faces = s.faces.reshape(-1, 4)[:, 1:]
    e = scene.add_cluster_ellipsoids(plotter, s.points * [2, 1, 1], faces, (0, 1, 0))
    assert e.mesh.n_cells == len(faces)
    with pytest.raises(ValueError, match="faces"):
        scene.add_cluster_ellipsoids(plotter, s.points, faces + len(s.points), (0, 1, 0))
    lips = scene.add_lips(plotter, s.points, faces, offset=(3, 0, 0))
    moved = s.points * 1.5
    lips.update(moved)
    np.testing.assert_allclose(lips.points, moved, atol=1e-5)
    np.testing.assert_allclose(s.points, pv.Sphere(radius=1.0).points)  # caller's array untouched
    markers = scene.add_lips(plotter, np.zeros((5, 3)), None, name="markers")
    assert markers.mesh.n_points == 5 and markers.mesh.n_cells <= 5
    with pytest.raises(ValueError, match="points"):
        markers.update(np.zeros((4, 3)))
