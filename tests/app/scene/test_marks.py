"""Landmark marks on the manifold: octahedra at frames, one colour each (any pyvista plotter)."""
from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

from app.scene.marks import add_landmark_marks


def test_marks_are_drawn_where_and_in_the_colours_given_then_hidden():
    p = pv.Plotter(off_screen=True)
    h = add_landmark_marks(p, size=0.1)
    assert not h.visible
    Y = np.array([[0.0, 0, 0, 9], [1.0, 2, 3, 9]])
    h.update(Y, [(1.0, 0, 0), (0, 0, 1.0)])
    assert h.visible and h.points.shape == (2, 3)
    np.testing.assert_array_equal(h.rgb, [[255, 0, 0], [0, 0, 255]])
    pts = np.asarray(h.mesh.points)
    assert pts.shape[0] == 2 * 6  # an octahedron's six vertices per mark
    np.testing.assert_allclose(pts[6:].mean(axis=0), [1.0, 2, 3], atol=1e-6)
    with pytest.raises(ValueError, match="colours must have shape \\(2, 3\\)"):
        h.update(Y, [(1.0, 0, 0)])
    h.update(None, None)
    assert not h.visible and len(h.points) == 0
    p.close()
