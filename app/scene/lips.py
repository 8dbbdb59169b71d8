"""The lip view's geometry: a mesh over the corpus faces, or markers as spheres."""
from __future__ import annotations

import numpy as np
import pyvista as pv

from app.scene.handles import Handle

__all__ = ["lip_mesh", "LipsHandle", "add_lips"]


def _points(points):
    P = np.array(points, dtype=np.float32)  # a copy: meshes must not share the caller's memory
    if P.ndim == 1:
        if P.size % 3:
            raise ValueError(f"a flat frame must hold 3 coordinates per point, got {P.size} values")
        P = P.reshape(-1, 3)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) == 0:
        raise ValueError(f"lip points must have shape (V, 3) with V > 0, got {P.shape}")
    return np.ascontiguousarray(P)


def lip_mesh(points, faces=None) -> pv.PolyData:
    """A PolyData of one frame: triangles over ``faces`` (F, 3), or bare points when None.

    Parameters
    ----------
    points : ndarray of shape (V, 3) (or a flat frame of 3V values)
    faces : ndarray of shape (F, 3) int or None
    """
    P = _points(points)
    if faces is None or len(faces) == 0:
        return pv.PolyData(P)
    Fc = np.asarray(faces, dtype=np.int64)
    if Fc.ndim != 2 or Fc.shape[1] != 3 or Fc.min() < 0 or Fc.max() >= len(P):
        raise ValueError(f"faces must be (F, 3) indices into {len(P)} points, got shape {Fc.shape} "
                         f"with indices {Fc.min() if Fc.size else 0}..{Fc.max() if Fc.size else 0}")
    return pv.PolyData(P, np.hstack([np.full((len(Fc), 1), 3, np.int64), Fc]).ravel())


class LipsHandle(Handle):
    """A lip mesh (or marker set) whose points are moved in place, frame by frame.

    ``offset`` (3,) is added to every frame (to show two trajectories side by side).
    """

    def __init__(self, plotter, mesh, actor, offset):
        super().__init__(plotter, mesh, actor)
        self.offset = np.asarray(offset, np.float32)

    def update(self, points) -> None:
        P = _points(points)
        if P.shape[0] != self.mesh.n_points:
            raise ValueError(f"frame has {P.shape[0]} points, the mesh has {self.mesh.n_points}")
        self.mesh.points[:] = P + self.offset
        if self.mesh.n_cells and "Normals" in self.mesh.point_data:
            self.mesh.compute_normals(cell_normals=False, split_vertices=False, inplace=True)
        self.mesh.Modified()

    @property
    def points(self) -> np.ndarray:
        return np.asarray(self.mesh.points) - self.offset


def add_lips(plotter, points, faces=None, *, color=(0.85, 0.45, 0.45), offset=(0.0, 0.0, 0.0),
             point_size: float = 8.0, name: str = "lips") -> LipsHandle:
    """Draw one lip frame; returns a handle whose :meth:`LipsHandle.update` moves it."""
    mesh = lip_mesh(points, faces)
    mesh.points[:] = mesh.points + np.asarray(offset, np.float32)
    if faces is None or len(faces) == 0:
        actor = plotter.add_mesh(mesh, color=color, point_size=point_size, render_points_as_spheres=True, name=name,
                                 pickable=False, reset_camera=False, render=False)
    else:
        mesh.compute_normals(cell_normals=False, split_vertices=False, inplace=True)
        actor = plotter.add_mesh(mesh, color=color, specular=0.3, name=name, pickable=False, reset_camera=False,
                                 render=False)
    return LipsHandle(plotter, mesh, actor, offset)
