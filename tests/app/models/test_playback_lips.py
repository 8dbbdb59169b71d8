"""Playback's per-frame lip normals (app.scene.lips.point_normals) are VTK's, computed in numpy."""
from __future__ import annotations

import numpy as np
import pytest

pv = pytest.importorskip("pyvista")

from app.scene.lips import add_lips, point_normals  # noqa: E402
from engine.talker.lipmodel import CONTROL_NAMES, LipModel  # noqa: E402


def _frame(lip, **kw):
    c = np.zeros((1, len(CONTROL_NAMES)))
    for k, v in kw.items():
        c[0, CONTROL_NAMES.index(k)] = v
    return lip.deform(c).reshape(-1, 3)


def test_moving_lip_normals_match_vtks_normals_filter():
    lip = LipModel("default")
    pl = pv.Plotter(off_screen=True, window_size=(160, 120))
    try:
        h = add_lips(pl, _frame(lip, jaw=0.2), lip.faces, offset=(40.0, 0.0, 0.0), names=lip.point_names)
        assert h._triangles is not None  # the fast path is the one taken for a triangle mesh
        for kw in ({"jaw": 1.0, "protrude": 1.0}, {"round": 0.8, "raise": -0.5}, {"closure": 1.0}):
            P = _frame(lip, **kw)
            h.update(P)
            ours = np.asarray(h.mesh.point_data["Normals"]).copy()
            ref = pv.PolyData(h.mesh.points.copy(), h.mesh.faces.copy())
            ref.compute_normals(cell_normals=False, split_vertices=False, inplace=True)
            assert np.abs(ours - np.asarray(ref.point_data["Normals"])).max() < 1e-4
            assert np.allclose(h.points, P, atol=1e-4)
    finally:
        pl.close()


def test_point_normals_of_a_folded_sheet():
    # two triangles folded along the x axis by 90 degrees: the shared edge's points get the
    # bisector, the others their own triangle's normal; an unused point gets zero
    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [5, 5, 5]], float)
    T = np.array([[0, 1, 2], [0, 3, 1]])
    N = point_normals(P, T)
    assert N.dtype == np.float32
    assert np.allclose(N[2], [0, 0, 1]) and np.allclose(N[3], [0, 1, 0])
    assert np.allclose(N[0], [0, np.sqrt(0.5), np.sqrt(0.5)]) and np.allclose(N[1], N[0])
    assert np.allclose(N[4], 0)


def test_lip_mesh_goes_to_the_mapper_without_a_python_filter_and_looks_the_same():
    """A playback frame renders the moved mesh itself: no pyvista smooth-shading filter re-runs per render
    (it cost about 1 ms a mesh a frame), and the picture is the one that filter gave, pixel for pixel."""
    lip = LipModel("default")
    frames = [_frame(lip, jaw=0.3), _frame(lip, jaw=1.0, protrude=1.0), _frame(lip, round=0.8, closure=0.6)]

    def draw(smooth_filter):
        add_mesh = pv.Plotter.add_mesh

        def through_filter(self, mesh, *a, **kw):  # the previous code's call, through pyvista's filters
            if "lip_rgb" not in mesh.point_data:
                return add_mesh(self, mesh, *a, **kw)
            kw.pop("color")
            return add_mesh(self, mesh, *a, smooth_shading=True, scalars="lip_rgb", rgb=True, show_scalar_bar=False,
                            **kw)

        pl = pv.Plotter(off_screen=True, window_size=(200, 140))
        try:
            pv.Plotter.add_mesh = through_filter if smooth_filter else add_mesh
            try:
                h = add_lips(pl, frames[0], lip.faces, color=(0.8, 0.3, 0.3), names=lip.point_names)
            finally:
                pv.Plotter.add_mesh = add_mesh
            pl.view_xy()
            pl.reset_camera()
            shots = []
            for P in frames[1:]:
                h.update(P)
                shots.append(np.asarray(pl.screenshot(return_img=True)).copy())
            producer = h.actor.GetMapper().GetInputAlgorithm()
            return shots, producer.GetClassName(), h.actor.GetProperty().GetInterpolation()
        finally:
            pl.close()

    shots, producer, interpolation = draw(smooth_filter=False)
    assert producer == "vtkTrivialProducer"  # the mesh itself, no Python algorithm in between
    assert interpolation == 2  # VTK_PHONG, as smooth_shading=True sets it
    ref, ref_producer, _ = draw(smooth_filter=True)
    assert ref_producer != "vtkTrivialProducer"  # the reference did go through pyvista's filter
    for a, b in zip(shots, ref):
        assert a.std() > 5  # the lips are drawn
        assert np.array_equal(a, b)
