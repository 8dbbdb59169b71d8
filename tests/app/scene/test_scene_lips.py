"""Sensors in the lip view (any pyvista plotter): spheres joined by straight lines, labelled, the aperture with its
value; a measured surface with the aperture over it; bare points stay spheres."""
from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui
pv = pytest.importorskip("pyvista")

P = np.array([[10.0, 0.0, 6.0], [8.0, -12.0, -8.0], [-2.0, 25.0, -1.0], [-5.0, -20.0, -30.0]])
ROLES = ["upper_lip", "lower_lip", "left_corner", "jaw"]
NAMES = ["UL", "LL", "ML", "JAW"]


@pytest.fixture
def plotter():
    p = pv.Plotter(off_screen=True, window_size=(240, 200))
    yield p
    p.close()


def _drawing(points=P, roles=ROLES, names=NAMES, dims=3, faces=None):
    from app.models.lip_drawing import drawing_of

    return drawing_of(points, dims=dims, roles=roles, names=names, faces=faces, unit="mm")


def test_sensors_are_spheres_straight_lines_labels_and_the_aperture(plotter):
    from app.scene import SensorsHandle, add_lips

    d = _drawing()
    h = add_lips(plotter, P, None, names=NAMES, drawing=d, offset=(1.0, 0, 0))
    assert isinstance(h, SensorsHandle)
    assert h.markers.n_points == 3 and h._other.n_points == 1  # the jaw sensor is not a lip sensor
    # UL-ML and ML-LL: straight lines, nothing interpolated; UL-LL is the aperture, a line of its own
    assert h.segments.n_lines == 2 and h.segments.n_points == 4
    assert h.aperture_value == pytest.approx(np.linalg.norm(P[0] - P[1]))
    assert h.label_texts == ["UL", "LL", "ML", "JAW", f"{np.linalg.norm(P[0] - P[1]):.1f} mm"]
    np.testing.assert_allclose(h.points, P, atol=1e-5)
    Q = P + [[0, 0, 2.0], [0, -3.0, 0], [0, 0, 0], [0, 0, 0]]
    h.update(Q)
    np.testing.assert_allclose(h.points, Q, atol=1e-5)
    np.testing.assert_allclose(np.asarray(h.aperture_line.points) - [1.0, 0, 0], Q[:2], atol=1e-5)
    assert h.label_texts[-1] == f"{np.linalg.norm(Q[0] - Q[1]):.1f} mm"
    drawn = {}
    for pts, actor, which in h._label_sets:  # each label set justified so its text runs away from its sensor
        arr = pts.GetPointData().GetAbstractArray("sensor_labels")
        drawn.update({k: arr.GetValue(j) for j, k in enumerate(which)})
        assert actor.GetMapper().GetPlaceAllLabels()  # never hidden where two would touch
    assert [drawn[k] for k in range(len(h.label_texts))] == h.label_texts
    for d, (ha, va) in zip(h._dirs, h._justify):  # the text runs away from its sensor
        assert {"left": d[0] > 0, "right": d[0] < 0}.get(ha, True)
        assert {"bottom": d[1] > 0, "top": d[1] < 0}.get(va, True)
    h.set_visible(False)
    assert not h.visible and not any(a.GetVisibility() for a in h.actors)
    plotter.render()
    with pytest.raises(ValueError, match="3 points, the sensors are 4"):
        h.update(P[:3])


def test_labels_of_close_sensors_stand_apart():
    """JAW just below LL (a Haskins recording): their labels do not stand on each other."""
    from app.scene.sensors import _label_directions

    ref = np.array([[0.0, 10.0], [0.0, -8.0], [22.0, 0.0], [-3.0, -9.5], [15.0, -10.0]])
    reach = 0.14 * 32.0
    dirs = _label_directions(ref, [0, 1, 2, 3, 4], reach)
    anchors = np.array([ref[i] + d * reach for i, d in enumerate(dirs)])
    gaps = [np.linalg.norm(a - b) for i, a in enumerate(anchors) for b in anchors[i + 1:]]
    assert min(gaps) >= 2.0 * reach - 1e-9


def test_a_profile_shows_where_the_face_looks(plotter):
    from app.scene import add_lips

    P2 = np.array([[0.0, 6.0, 0.0], [0.5, -6.0, 0.0], [-10.0, -14.0, 0.0]])  # UL, LL, LI in profile (x forward)
    d = _drawing(P2, ["upper_lip", "lower_lip", "jaw"], ["UL", "LL", "LI"], dims=2)
    assert d.view == "profile" and d.forward == (1.0, 0.0)
    h = add_lips(plotter, P2, None, drawing=d)
    assert h.label_texts[-1] == "front" and h._arrow.n_points > 0
    tip = np.asarray(h._arrow.points)
    assert np.ptp(tip[:, 0]) > 3 * np.ptp(tip[:, 1])  # the arrow points along x, forward


def test_a_measured_surface_stays_a_surface_with_the_aperture_over_it(plotter):
    from app.scene import LipsHandle, add_lips

    mesh = pv.Sphere(theta_resolution=8, phi_resolution=6)
    pts = np.asarray(mesh.points, np.float64)
    faces = np.asarray(mesh.faces).reshape(-1, 4)[:, 1:]
    roles = [""] * len(pts)
    roles[int(np.argmax(pts[:, 1]))], roles[int(np.argmin(pts[:, 1]))] = "upper_lip", "lower_lip"
    d = _drawing(pts, roles, None, faces=faces)
    h = add_lips(plotter, pts, faces, drawing=d)
    assert isinstance(h, LipsHandle) and h.mesh.n_cells == len(faces)
    assert h.overlay is not None and h.overlay.markers is None and h.overlay.label_texts == ["1.0 mm"]
    h.update(pts * 2)
    assert h.overlay.aperture_value == pytest.approx(2 * np.ptp(pts[:, 1]), rel=1e-5)


def test_points_without_names_or_roles_stay_spheres(plotter):
    from app.scene import LipsHandle, add_lips

    h = add_lips(plotter, P, None)
    assert isinstance(h, LipsHandle) and h.mesh.n_points == 4 and h.mesh.n_cells == 4
