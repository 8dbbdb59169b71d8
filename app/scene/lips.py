"""The lip view's geometry: a mesh over the corpus faces, or sparse markers as a lip contour.

With no faces and 3 to 20 lip points (by their roles), the markers are drawn as lips:
a tube along the interpolated outer lip contour (:class:`engine.recordings.lipcontour.LipContour`),
the markers as spheres and a label per sensor; otherwise as bare spheres.
"""
from __future__ import annotations

import numpy as np
import pyvista as pv

from app.scene.handles import Handle

__all__ = ["lip_mesh", "point_normals", "LipsHandle", "ContourHandle", "add_lips", "add_lip_contour", "lip_colours", "SKIN",
           "mouth_interior", "MOUTH"]


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
    interior behind a synthetic lip mesh).
    """

    def __init__(self, plotter, mesh, actor, offset, extras=()):
        super().__init__(plotter, mesh, actor)
        self.offset = np.asarray(offset, np.float32)
        self.extras = tuple(extras)
        # the triangles as VTK's normals filter left them (consistently ordered), for the
        # per-frame normals in numpy (vtkPolyDataNormals through pyvista: ~1.6 ms a frame)
        cells = np.asarray(mesh.faces) if mesh.n_cells else np.zeros(0, np.int64)
        tri = cells.reshape(-1, 4) if cells.size and cells.size % 4 == 0 else None
        self._triangles = tri[:, 1:].astype(np.int64) if tri is not None and (tri[:, 0] == 3).all() else None

    def set_visible(self, visible: bool) -> None:
        super().set_visible(visible)
        for a in self.extras:
            a.SetVisibility(bool(visible))

    def remove(self) -> None:
        super().remove()
        for a in self.extras:
            self.plotter.remove_actor(a, render=False)

    def update(self, points) -> None:
        P = _points(points)
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

    @property
    def points(self) -> np.ndarray:
        return np.asarray(self.mesh.points) - self.offset


class ContourHandle(LipsHandle):
    """Sparse lip markers drawn as a contour tube, sphere markers and sensor labels, moved frame by frame.

    ``mesh`` is the tube; ``markers`` the markers' PolyData; ``contour`` the fitted
    :class:`engine.recordings.lipcontour.LipContour`; ``labels`` the label actor (or None).
    """

    def __init__(self, plotter, mesh, actor, offset, contour, markers, marker_actor, labels, label_points):
        super().__init__(plotter, mesh, actor, offset)
        self.contour = contour
        self.markers, self.marker_actor = markers, marker_actor
        self.labels, self.label_points = labels, label_points
        self._n = markers.n_points

    def update(self, points) -> None:
        P = _points(points)
        if P.shape[0] != self._n:
            raise ValueError(f"frame has {P.shape[0]} points, the lip markers are {self._n}")
        self.mesh.points[:] = self.contour.transform(P) + self.offset
        # the tube's triangles as add_lip_contour's normals filter ordered them: VTK's normals, in numpy
        self.mesh.point_data["Normals"][:] = point_normals(self.mesh.points, self._triangles)
        self.mesh.Modified()
        self.markers.points[:] = P + self.offset
        self.markers.Modified()
        if self.label_points is not None:
            self.label_points.points[:] = P + self.offset
            self.label_points.Modified()

    @property
    def points(self) -> np.ndarray:
        return np.asarray(self.markers.points) - self.offset

    def set_visible(self, visible: bool) -> None:
        for a in (self.actor, self.marker_actor, self.labels):
            if a is not None:
                a.SetVisibility(bool(visible))

    def remove(self) -> None:
        for a in (self.actor, self.marker_actor, self.labels):
            if a is not None:
                self.plotter.remove_actor(a, render=False)


def add_lip_contour(plotter, points, roles=None, names=None, *, color=(0.85, 0.45, 0.45), offset=(0.0, 0.0, 0.0),
                    point_size: float = 10.0, name: str = "lips", labels: bool = True,
                    reference=None) -> ContourHandle:
    """Draw sparse lip markers as lips: contour tube + spheres + sensor labels.

    Parameters
    ----------
    plotter : any pyvista plotter
    points : ndarray of shape (V, 3)
        The frame drawn.
    roles : sequence of str or None
        Point roles (``Corpus.point_roles``); lip roles form the contour, others are
        drawn as markers only. None: every point is on the contour.
    names : sequence of str or None
        Sensor names for the labels.
    reference : ndarray of shape (V, 3), optional
        Frame that fixes the contour's point order (default: ``points``; pass the mean frame).

    Raises
    ------
    ValueError
        When the points cannot form a contour (fewer than 3 or more than 20 lip points).
    """
    from engine.recordings.lipcontour import LipContour

    P = _points(points)
    off = np.asarray(offset, np.float32)
    contour = LipContour().fit(_points(reference) if reference is not None else P, roles)
    tube = pv.PolyData(contour.transform(P) + off,
                       np.hstack([np.full((len(contour.faces_), 1), 3, np.int64), contour.faces_]).ravel())
    tube.compute_normals(cell_normals=False, split_vertices=False, inplace=True)
    # Phong over the tube's own normals, without pyvista's per-render smooth-shading filter (see add_lips)
    actor = plotter.add_mesh(tube, color=color, specular=0.3, name=name, pickable=False, reset_camera=False,
                             render=False)
    actor.prop.interpolation = "phong"
    markers = pv.PolyData(P + off)
    marker_actor = plotter.add_mesh(markers, color=(0.15, 0.15, 0.15), point_size=point_size,
                                    render_points_as_spheres=True, name=f"{name}_markers", pickable=False,
                                    reset_camera=False, render=False)
    label_actor, label_points = None, None
    if labels and names is not None:
        label_points = pv.PolyData(P + off)
        label_actor = plotter.add_point_labels(label_points, [str(n) for n in names], font_size=12,
                                               point_size=1, shape_opacity=0.4, name=f"{name}_labels",
                                               always_visible=True, render=False, reset_camera=False)
    return ContourHandle(plotter, tube, actor, off, contour, markers, marker_actor, label_actor, label_points)


def add_lips(plotter, points, faces=None, *, color=(0.85, 0.45, 0.45), offset=(0.0, 0.0, 0.0),
             point_size: float = 8.0, name: str = "lips", roles=None, names=None) -> LipsHandle:
    """Draw one lip frame; returns a handle whose :meth:`LipsHandle.update` moves it.

    Without ``faces``, markers with roles (or names) that can form a lip contour are
    drawn as one (:func:`add_lip_contour`); otherwise as spheres. A mesh is smooth-shaded;
    with the synthetic lip model's point names its vermilion takes ``color``, the skin
    around it a skin tone (:func:`lip_colours`), and a dark mouth interior is drawn behind
    it (:func:`mouth_interior`).
    """
    if (faces is None or len(faces) == 0) and (roles is not None or names is not None):
        try:
            return add_lip_contour(plotter, points, roles, names, color=color, offset=offset, name=name)
        except ValueError:
            pass  # not a lip marker set: spheres below
    mesh = lip_mesh(points, faces)
    mesh.points[:] = mesh.points + np.asarray(offset, np.float32)
    if faces is None or len(faces) == 0:
        actor = plotter.add_mesh(mesh, color=color, point_size=point_size, render_points_as_spheres=True, name=name,
                                 pickable=False, reset_camera=False, render=False)
    else:
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
        return LipsHandle(plotter, mesh, actor, offset, extras)
    return LipsHandle(plotter, mesh, actor, offset)


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
