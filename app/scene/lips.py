"""The lip view's geometry: a measured surface over the corpus faces, or the sensors as sensors.

What is drawn follows :class:`app.models.lip_drawing.LipDrawing` (the figures follow it too): a
corpus with faces (a mesh sequence, FaceMesh landmarks tracked in a video, the synthetic
talker's lip model) is that surface, smooth-shaded, with the lip aperture over it when the
point roles give it; sensors are spheres joined by straight lines with labels and the aperture
(:mod:`app.scene.sensors`). Nothing is interpolated between sensors.
"""
from __future__ import annotations

import numpy as np
import pyvista as pv

from app.scene.handles import Handle
from app.scene.sensors import add_sensors, as_points

__all__ = ["lip_mesh", "point_normals", "LipsHandle", "add_lips", "lip_colours", "SKIN", "mouth_interior", "MOUTH"]


def lip_mesh(points, faces=None) -> pv.PolyData:
    """A PolyData of one frame: triangles over ``faces`` (F, 3), or bare points when None.

    Parameters
    ----------
    points : ndarray of shape (V, 3) (or a flat frame of 3V values)
    faces : ndarray of shape (F, 3) int or None
    """
    P = as_points(points)
    if faces is None or len(faces) == 0:
        return pv.PolyData(P)
    Fc = np.asarray(faces, dtype=np.int64)
    if Fc.ndim != 2 or Fc.shape[1] != 3 or Fc.min() < 0 or Fc.max() >= len(P):
        raise ValueError(f"faces must be (F, 3) indices into {len(P)} points, got shape {Fc.shape} "
                         f"with indices {Fc.min() if Fc.size else 0}..{Fc.max() if Fc.size else 0}")
    return pv.PolyData(P, np.hstack([np.full((len(Fc), 1), 3, np.int64), Fc]).ravel())


def point_normals(points, triangles) -> np.ndarray:
    """Smooth-shading point normals, as VTK's normals filter without vertex splitting computes them.

    Each point's normal is the normalised sum of the unit normals of the triangles
    around it (unweighted, as ``vtkPolyDataNormals``); a point in no triangle, or whose
    triangles cancel, gets (0, 0, 0).

    Parameters
    ----------
    points : ndarray of shape (V, 3)
    triangles : ndarray of shape (F, 3) int
        Point indices of each triangle, counter-clockwise seen from the normal's side.

    Returns
    -------
    ndarray of shape (V, 3) float32
    """
    P = np.asarray(points, np.float64)
    T = np.asarray(triangles, np.int64)
    n = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    idx = T.ravel()
    acc = np.column_stack([np.bincount(idx, np.repeat(n[:, j], 3), minlength=len(P)) for j in range(3)])
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    return np.divide(acc, length, out=np.zeros_like(acc), where=length > 0).astype(np.float32)


class LipsHandle(Handle):
    """A lip mesh (or marker set) whose points are moved in place, frame by frame.

    ``offset`` (3,) is added to every frame (to show two trajectories side by side).
    ``extras``: further actors shown, hidden and removed with the lips (the mouth's dark
    interior behind a synthetic lip mesh). ``overlay``: a :class:`app.scene.sensors.SensorsHandle`
    moved with the lips (the aperture over a measured surface), or None.
    """

    def __init__(self, plotter, mesh, actor, offset, extras=(), overlay=None):
        super().__init__(plotter, mesh, actor)
        self.offset = np.asarray(offset, np.float32)
        self.extras = tuple(extras)
        self.overlay = overlay
        # the triangles as VTK's normals filter left them (consistently ordered), for the
        # per-frame normals in numpy (vtkPolyDataNormals through pyvista: ~1.6 ms a frame)
        cells = np.asarray(mesh.faces) if mesh.n_cells else np.zeros(0, np.int64)
        tri = cells.reshape(-1, 4) if cells.size and cells.size % 4 == 0 else None
        self._triangles = tri[:, 1:].astype(np.int64) if tri is not None and (tri[:, 0] == 3).all() else None

    def set_visible(self, visible: bool) -> None:
        super().set_visible(visible)
        for a in self.extras:
            a.SetVisibility(bool(visible))
        if self.overlay is not None:
            self.overlay.set_visible(visible)

    def set_colour(self, color) -> None:
        """The surface's (or markers') colour."""
        self.actor.prop.color = color

    def remove(self) -> None:
        super().remove()
        for a in self.extras:
            self.plotter.remove_actor(a, render=False)
        if self.overlay is not None:
            self.overlay.remove()

    def update(self, points) -> None:
        P = as_points(points)
        if P.shape[0] != self.mesh.n_points:
            raise ValueError(f"frame has {P.shape[0]} points, the mesh has {self.mesh.n_points}")
        self.mesh.points[:] = P + self.offset
        if self.mesh.n_cells and "Normals" in self.mesh.point_data:
            if self._triangles is not None:
                self.mesh.point_data["Normals"][:] = point_normals(self.mesh.points, self._triangles)
            else:
                # VTK's normals filter passes an existing "Normals" array through: drop it first
                del self.mesh.point_data["Normals"]
                self.mesh.compute_normals(cell_normals=False, split_vertices=False, inplace=True)
        self.mesh.Modified()
        if self.overlay is not None:
            self.overlay.update(P)

    @property
    def points(self) -> np.ndarray:
        return np.asarray(self.mesh.points) - self.offset


def add_lips(plotter, points, faces=None, *, color=(0.85, 0.45, 0.45), offset=(0.0, 0.0, 0.0),
             point_size: float = 8.0, name: str = "lips", names=None, drawing=None, labels: bool = True):
    """Draw one lip frame; returns a handle whose ``update(points)`` moves it.

    With a ``drawing`` (:func:`app.models.lip_drawing.lip_drawing` of the corpus) its sensors are
    drawn as sensors (:func:`app.scene.sensors.add_sensors`: spheres, straight lines, labels when
    ``labels``, the aperture) and a measured surface as a surface with the aperture over it.
    Without one: a mesh over ``faces``, or bare spheres. A mesh is smooth-shaded; with the
    synthetic lip model's point names (``names``) its vermilion takes ``color``, the skin around it
    a skin tone (:func:`lip_colours`), and a dark mouth interior is drawn behind it
    (:func:`mouth_interior`).
    """
    if drawing is not None and drawing.kind != "surface":
        return add_sensors(plotter, drawing, points, color=color, offset=offset, name=name, labels=labels,
                           point_size=max(point_size, 12.0) if drawing.kind == "sensors" else point_size)
    mesh = lip_mesh(points, faces)
    mesh.points[:] = mesh.points + np.asarray(offset, np.float32)
    if faces is None or len(faces) == 0:
        actor = plotter.add_mesh(mesh, color=color, point_size=point_size, render_points_as_spheres=True, name=name,
                                 pickable=False, reset_camera=False, render=False)
        return LipsHandle(plotter, mesh, actor, offset)
    # smooth (Gouraud) shading over point normals shared by the triangles around each
    # point: no facets, and no per-triangle colour steps that show as seams in exports
    mesh.compute_normals(cell_normals=False, split_vertices=False, inplace=True)
    rgb = lip_colours(mesh.n_points, color, names)
    extras = []
    if rgb is not None:
        mesh.point_data["lip_rgb"] = rgb
        mesh.point_data.active_scalars_name = "lip_rgb"
        extras.append(plotter.add_mesh(mouth_interior(np.asarray(mesh.points)), color=MOUTH, lighting=False,
                                       name=f"{name}_interior", pickable=False, reset_camera=False,
                                       render=False))
    # the mesh goes to the mapper as it is: pyvista's smooth_shading=True and scalars= would put its
    # Python smooth-shading and active-scalars filters in between, which re-run at every render of a
    # moved frame (2.4 ms of a playback frame's two meshes) for the same picture. The mesh carries
    # its own point normals (LipsHandle.update keeps them): Phong-shaded, as smooth_shading sets it.
    # (coloured by the per-point RGB, the property keeps the colour pyvista gives a scalar-coloured
    # mesh: it tints the specular highlight, as before)
    actor = plotter.add_mesh(mesh, color=color if rgb is None else plotter.renderer.next_color, specular=0.25,
                             specular_power=12.0, name=name, pickable=False, reset_camera=False, render=False)
    actor.prop.interpolation = "phong"
    if rgb is not None:  # coloured by the per-point RGB itself, as scalars="lip_rgb", rgb=True did
        mapper = actor.GetMapper()
        mapper.SetScalarModeToUsePointData()
        mapper.SetColorModeToDirectScalars()
        mapper.SetArrayName("lip_rgb")
        mapper.ScalarVisibilityOn()
    overlay = None
    if drawing is not None and drawing.has_aperture:  # the aperture over the measured surface
        overlay = add_sensors(plotter, drawing, points, offset=offset, name=f"{name}_overlay", labels=False,
                              markers=False)
    return LipsHandle(plotter, mesh, actor, offset, extras, overlay)


#: colour of the mouth's interior seen through the lips' aperture
MOUTH = (0.16, 0.05, 0.06)


def mouth_interior(points) -> pv.PolyData:
    """A dark rounded rectangle (superellipse) behind a synthetic lip mesh (points (V, 3) of one
    frame, mm): 0.84 of the mesh's width across, from 8 mm above to 24 mm below its vertical
    centre, 3 mm behind its deepest point. The skin of the mesh hides it everywhere but
    through the aperture."""
    P = np.asarray(points, np.float64)
    lo, hi = P.min(0), P.max(0)
    cx = 0.5 * (lo[0] + hi[0])
    cy = float(np.median(P[:, 1]))
    t = np.linspace(0, 2 * np.pi, 96, endpoint=False)
    rx, ry = 0.42 * (hi[0] - lo[0]), 16.0
    c, sn = np.cos(t), np.sin(t)
    sx, sy = np.sign(c) * np.abs(c) ** 0.5, np.sign(sn) * np.abs(sn) ** 0.5  # superellipse, exponent 4
    ring = np.column_stack([cx + rx * sx, cy - 8.0 + ry * sy, np.full(len(t), lo[2] - 3.0)])
    return pv.PolyData(ring.astype(np.float32), np.r_[len(t), np.arange(len(t))])


#: the skin colour the lip colour is blended towards outside the vermilion
SKIN = (0.93, 0.80, 0.70)


def lip_colours(n_points: int, color, names=None) -> np.ndarray | None:
    """Per-point RGB (uint8, (V, 3)) for a lip mesh: ``color`` on the vermilion, blended
    towards :data:`SKIN` on the surrounding skin, when the point names are the synthetic
    lip model's (``engine.talker.lipmodel.vermilion_weight``); None otherwise (one colour)."""
    if names is None or len(names) != n_points:
        return None
    from engine.talker.lipmodel import vermilion_weight

    w = vermilion_weight(list(names))
    if w is None:
        return None
    c = np.asarray(pv.Color(color).float_rgb, np.float64)
    skin = 0.3 * c + 0.7 * np.asarray(SKIN)
    rgb = w[:, None] * c[None, :] + (1 - w[:, None]) * skin[None, :]
    return np.round(255 * rgb).astype(np.uint8)
