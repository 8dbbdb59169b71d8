"""Scene elements of the manifold view: points, plane, directions, trajectories, paths, ellipsoids.

Colours follow the paper's figures: original trajectories black, generated ones
red; density and similarity run blue -> red (see :mod:`app.models.state`).
"""
from __future__ import annotations

import numpy as np
import pyvista as pv

from app.models.colour_maps import RESERVED_COLOURS as _R
from app.scene.handles import Handle

__all__ = ["PointsHandle", "LocalFrameHandle", "PolylineHandle", "add_manifold_points", "add_zero_velocity_plane",
           "add_global_axes", "label_zoom", "add_local_frame", "add_point_markers", "add_trajectory", "add_state_path",
           "add_cluster_ellipsoids", "EllipsoidHandle", "outline_colour", "direction_arrows", "DIRECTION_ARROWS",
           "add_marker", "MarkerHandle", "scene_scale", "overlay_renderer", "move_to_overlay", "to_rgb8",
           "ORIGINAL_COLOUR", "SYNTHETIC_COLOUR", "PATH_COLOUR",
           "S_COLOUR", "V_COLOUR", "NORMAL_COLOUR", "PLANE_COLOUR"]

# each glyph's colour is declared once (app.models.colour_maps.RESERVED_COLOURS), where the legend reads it
ORIGINAL_COLOUR = _R["original trajectory"]   # black, as the paper's original trajectories
SYNTHETIC_COLOUR = _R["synthetic trajectory"]  # red, as the paper's generated ones
PATH_COLOUR = _R["state path"]
S_COLOUR = _R["S"]                             # dark green, as in the figure set
V_COLOUR = _R["V"]                             # dark magenta
NORMAL_COLOUR = _R["normal"]
PLANE_COLOUR = _R["plane"]


def _xyz(a, what, n=None):
    a = np.asarray(a, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] < 3:
        raise ValueError(f"{what} must have shape (n, 3) (extra columns ignored), got {a.shape}")
    if n is not None and a.shape[0] < n:
        raise ValueError(f"{what} needs at least {n} rows, got {a.shape[0]}")
    return np.ascontiguousarray(a[:, :3])


def _vec(v, what):
    v = np.asarray(v, dtype=np.float64).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{what} must be 3 finite numbers, got {v!r}")
    return v


def scene_scale(Fy3) -> float:
    """A length for glyphs: the largest extent of the point cloud (1 if degenerate)."""
    Y = _xyz(Fy3, "Fy3")
    ext = float((Y.max(0) - Y.min(0)).max()) if len(Y) else 0.0
    return ext if ext > 0 else 1.0


def to_rgb8(rgb) -> np.ndarray:
    """Float RGB in [0, 1] (n, 3) -> uint8 (n, 3)."""
    rgb = np.asarray(rgb)
    if rgb.dtype == np.uint8:
        return rgb
    return np.clip(np.rint(np.asarray(rgb, np.float64) * 255), 0, 255).astype(np.uint8)


class PointsHandle(Handle):
    """The manifold's point cloud; colours change in place.

    ``mesh.point_data["rgb"]`` holds the shown colours (uint8) and
    ``mesh.point_data["value"]`` the scalar they encode (NaN = no value, e.g. an
    unreachable state), so tests and tools can read what is drawn.
    """

    #: frame index of each drawn point (None: point i is frame i); see :func:`app.models.lod.cloud_detail`
    frames = None

    def frame_of(self, point_id) -> int:
        """The frame a drawn point (its id in the mesh) shows."""
        return int(point_id) if self.frames is None else int(self.frames[int(point_id)])

    def set_colors(self, rgb, values=None) -> None:
        """Colours (and values) of the drawn points, or of every frame when only some are drawn."""
        rgb8 = to_rgb8(rgb)
        n = self.mesh.n_points
        if self.frames is not None and rgb8.shape[0] != n:  # one colour per frame: keep the drawn frames'
            rgb8 = rgb8[self.frames]
            values = None if values is None else np.asarray(values)[self.frames]
        if rgb8.shape != (n, 3):
            raise ValueError(f"colours must have shape ({n}, 3), got {rgb8.shape}")
        self.mesh.point_data["rgb"][:] = rgb8
        v = np.full(n, np.nan, np.float32) if values is None else np.asarray(values, np.float32)
        if v.shape != (n,):
            raise ValueError(f"values must have shape ({n},), got {v.shape}")
        self.mesh.point_data["value"][:] = v
        self.mesh.Modified()

    @property
    def rgb(self) -> np.ndarray:
        return np.asarray(self.mesh.point_data["rgb"])

    @property
    def values(self) -> np.ndarray:
        return np.asarray(self.mesh.point_data["value"])


def add_manifold_points(plotter, Fy3, rgb=None, values=None, *, point_size: float = 6.0, spheres: bool = True,
                        name: str = "manifold_points", frames=None) -> PointsHandle:
    """Draw F^y as points coloured per point.

    Parameters
    ----------
    plotter : pyvista plotter
    Fy3 : ndarray of shape (N, >=3)
        Only the first three columns are drawn.
    rgb : ndarray of shape (N, 3), float in [0, 1] or uint8, optional (default grey)
    values : ndarray of shape (N,), optional
        The scalar the colours encode.
    spheres : bool, default=True
        Shade each point as a small sphere; False draws flat dots, several times cheaper
        per frame in software OpenGL (the explorer's choice for large clouds).
    frames : ndarray of int, optional
        Draw only these frames (level of detail, :func:`app.models.lod.cloud_detail`); the
        handle's ``frame_of`` maps a drawn point back to its frame and ``set_colors``
        accepts one colour per frame.
    """
    if frames is not None:
        frames = np.asarray(frames, dtype=np.int64)
        Y = _xyz(np.asarray(Fy3)[frames], "Fy3", 1)  # only the drawn rows are read (F^y may be on disk)
    else:
        Y = _xyz(Fy3, "Fy3", 1)
    mesh = pv.PolyData(Y.astype(np.float32))
    n = len(Y)
    mesh.point_data["rgb"] = np.full((n, 3), 160, np.uint8) if rgb is None else np.zeros((n, 3), np.uint8)
    mesh.point_data["value"] = np.full(n, np.nan, np.float32)
    actor = plotter.add_mesh(mesh, scalars="rgb", rgb=True, point_size=point_size,
                             render_points_as_spheres=bool(spheres), name=name, pickable=True, show_scalar_bar=False,
                             reset_camera=False, render=False)
    h = PointsHandle(plotter, mesh, actor)
    h.frames = frames
    if rgb is not None:
        h.set_colors(rgb, values)
    return h


def add_point_markers(plotter, Y, color, *, point_size: float = 8.0, spheres: bool = True,
                      name: str = "markers") -> Handle:
    """Plain points of one colour (e.g. a phone's cluster members), not pickable; ``spheres``: shaded
    as small spheres, else flat dots (several times cheaper per frame in software OpenGL)."""
    mesh = pv.PolyData(_xyz(Y, "points", 1).astype(np.float32))
    actor = plotter.add_mesh(mesh, color=color, point_size=point_size, render_points_as_spheres=bool(spheres),
                             name=name, pickable=False, reset_camera=False, render=False)
    return Handle(plotter, mesh, actor)


def add_zero_velocity_plane(plotter, point, normal, size: float, *, color=PLANE_COLOUR, opacity: float = 0.18,
                            name: str = "zero_velocity_plane") -> Handle:
    """The zero-velocity plane through ``point`` with unit ``normal`` (the global V), ``size`` wide."""
    point, normal = _vec(point, "plane point"), _vec(normal, "plane normal")
    if np.linalg.norm(normal) == 0:
        raise ValueError("plane normal must be non-zero")
    plane = pv.Plane(center=point, direction=normal, i_size=float(size), j_size=float(size),
                     i_resolution=8, j_resolution=8)
    actor = plotter.add_mesh(plane, color=color, opacity=opacity, show_edges=True, edge_color=(0.4, 0.4, 0.45),
                             line_width=1, name=name, pickable=False, reset_camera=False, render=False)
    return Handle(plotter, plane, actor)


def _arrow(start, direction, length):
    d = _vec(direction, "direction")
    nd = np.linalg.norm(d)
    if nd == 0 or length <= 0:
        return pv.PolyData(np.asarray([start], np.float32))
    return pv.Arrow(start=_vec(start, "arrow start"), direction=d / nd, scale=float(length),
                    tip_length=0.25, tip_radius=0.08, shaft_radius=0.025)


def add_global_axes(plotter, origin, S, V, length: float, *, labels: bool = True) -> dict:
    """Arrows for the global shape direction S (green) and velocity direction V (magenta).

    Returns dict ``{"S": Handle, "V": Handle}``.
    """
    out = {}
    for key, vec, col in (("S", S, S_COLOUR), ("V", V, V_COLOUR)):
        mesh = _arrow(origin, vec, length)
        actor = plotter.add_mesh(mesh, color=col, name=f"global_{key}", pickable=False, reset_camera=False,
                                 render=False, smooth_shading=True)
        out[key] = Handle(plotter, mesh, actor)
    if labels:
        o = _vec(origin, "origin")
        tips = np.array([o + 1.08 * length * _vec(S, "S") / max(np.linalg.norm(S), 1e-12),
                         o + 1.08 * length * _vec(V, "V") / max(np.linalg.norm(V), 1e-12)])
        out["labels"] = plotter.add_point_labels(tips, ["S", "V"], font_size=AXES_LABEL_PX, text_color="black",
                                                 shape=None, show_points=False, name="global_axes_labels",
                                                 always_visible=True, pickable=False, reset_camera=False, render=False)
        out["tips"] = tips  # where the labels stand (views keep them on screen: label_zoom)
    return out


#: font size (pixels) of the S and V labels
AXES_LABEL_PX = 14


def label_zoom(xy, size, *, pad: float = 1.5 * AXES_LABEL_PX) -> float:
    """The camera zoom (<= 1) that keeps labels at display positions ``xy`` (n, 2) at least ``pad`` pixels
    inside a viewport of ``size`` (width, height); 1 when they already are.

    Zooming scales display offsets from the viewport's centre by the factor (exactly in a parallel
    projection, nearly so in perspective), so the factor is the smallest ratio of the room left to
    each label's offset, per axis.
    """
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    half = 0.5 * np.asarray(size, dtype=np.float64)
    off = np.abs(xy - half)
    room = np.maximum(half - pad, 1.0)
    with np.errstate(divide="ignore"):
        ratio = np.where(off > 0, room / off, np.inf)
    return float(min(1.0, ratio.min())) if ratio.size else 1.0


def _placement(point, direction, length):
    """A 4x4 matrix that maps the unit arrow along +x to ``length`` along ``direction`` from ``point``."""
    d = _vec(direction, "direction")
    d = d / np.linalg.norm(d)
    helper = np.eye(3)[int(np.argmin(np.abs(d)))]  # the axis least parallel to d
    u = np.cross(d, helper)
    u /= np.linalg.norm(u)
    w = np.cross(d, u)
    M = np.eye(4)
    M[:3, :3] = float(length) * np.column_stack([d, u, w])
    M[:3, 3] = _vec(point, "arrow start")
    return M


class LocalFrameHandle:
    """The local frame (s_i, v_i, normal) at one point; :meth:`update` moves it in place.

    Each arrow is one unit arrow built once; a click only changes its actor's user
    matrix (position, direction, length), so no geometry is rebuilt or re-uploaded.
    """

    COLOURS = {"s": _R["local s"], "v": _R["local v"], "normal": NORMAL_COLOUR}

    def __init__(self, plotter, length: float):
        from vtkmodules.vtkCommonMath import vtkMatrix4x4

        self.plotter = plotter
        self.length = float(length)
        self.parts = {}
        self._matrices = {}
        for key, col in self.COLOURS.items():
            mesh = _arrow((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 1.0)
            actor = plotter.add_mesh(mesh, color=col, name=f"local_{key}", pickable=False, reset_camera=False,
                                     render=False)
            self._matrices[key] = vtkMatrix4x4()
            actor.SetUserMatrix(self._matrices[key])
            self.parts[key] = Handle(plotter, mesh, actor)
        self.set_visible(False)

    def update(self, point, s, v, normal) -> None:
        point = _vec(point, "frame point")
        shown = {}
        for key, vec in (("s", s), ("v", v), ("normal", normal)):
            vec = _vec(vec, f"local {key}")
            shown[key] = bool(np.linalg.norm(vec) > 0 and self.length > 0)
            if shown[key]:
                M = _placement(point, vec, self.length)
                mat = self._matrices[key]
                for r in range(4):
                    for c in range(4):
                        mat.SetElement(r, c, float(M[r, c]))
                mat.Modified()
                self.parts[key].actor.Modified()
        for key, on in shown.items():
            self.parts[key].set_visible(on)

    def bounds(self, key) -> tuple:
        """World bounds of one drawn arrow (its unit geometry under its matrix)."""
        return tuple(self.parts[key].actor.GetBounds())

    def set_visible(self, visible: bool) -> None:
        for h in self.parts.values():
            h.set_visible(visible)

    @property
    def visible(self) -> bool:
        return all(h.visible for h in self.parts.values())


def add_local_frame(plotter, point=None, s=None, v=None, normal=None, *, length: float = 1.0) -> LocalFrameHandle:
    """Arrows for a frame's local shape s_i (light green), velocity v_i (pink) and normal (blue).

    Created hidden when ``point`` is None; call ``handle.update(point, s, v, normal)``.
    """
    h = LocalFrameHandle(plotter, length)
    if point is not None:
        h.update(point, s, v, normal)
    return h


class PolylineHandle(Handle):
    """A polyline (trajectory or state path); :meth:`update` redraws it in place.

    With ``arrow_size`` > 0 cones along the line point the way it runs (its first point to its
    last): :data:`DIRECTION_ARROWS` of them, evenly spaced along its length, the last at its end.
    """

    def __init__(self, plotter, mesh, actor, *, node_radius: float = 0.0, arrow_size: float = 0.0):
        super().__init__(plotter, mesh, actor)
        self.node_radius = float(node_radius)
        self.arrow_size = float(arrow_size)
        self.points = np.zeros((0, 3))
        self.arrows = (np.zeros((0, 3)), np.zeros((0, 3)))  # (positions, unit directions) of the cones drawn

    def update(self, Y) -> None:
        Y = _xyz(Y, "polyline points") if Y is not None and len(Y) else np.zeros((0, 3))
        self.points = Y
        self.arrows = direction_arrows(Y) if self.arrow_size > 0 else (np.zeros((0, 3)), np.zeros((0, 3)))
        self.replace_geometry(_polyline(Y, self.node_radius, self.arrows, self.arrow_size))
        self.set_visible(len(Y) > 0)


#: cones drawn along a trajectory or path to show its direction
DIRECTION_ARROWS = 5


def direction_arrows(Y, count: int = DIRECTION_ARROWS) -> tuple[np.ndarray, np.ndarray]:
    """Where the direction cones of a polyline ``Y`` (n, 3) stand and which way they point.

    ``count`` positions evenly spaced along the line's length, the last at its end (the
    first a full spacing in); each points along the line's segment there, first point to
    last. A line of fewer than two distinct points has none.

    Returns
    -------
    positions, directions : ndarray of shape (k, 3)
    """
    Y = np.asarray(Y, dtype=np.float64)
    if len(Y) < 2:
        return np.zeros((0, 3)), np.zeros((0, 3))
    seg = np.diff(Y, axis=0)
    length = np.linalg.norm(seg, axis=1)
    keep = length > 0
    if not keep.any():
        return np.zeros((0, 3)), np.zeros((0, 3))
    seg, length, start = seg[keep], length[keep], Y[:-1][keep]
    cum = np.r_[0.0, np.cumsum(length)]
    at = cum[-1] * np.arange(1, count + 1) / count
    k = np.clip(np.searchsorted(cum, at, side="left") - 1, 0, len(seg) - 1)
    u = seg[k] / length[k, None]
    pos = start[k] + (at - cum[k])[:, None] * u
    return pos, u


def _polyline(Y, node_radius=0.0, arrows=None, arrow_size=0.0):
    if len(Y) == 0:
        return pv.PolyData(np.zeros((1, 3), np.float32))
    line = pv.lines_from_points(Y) if len(Y) > 1 else pv.PolyData(Y)
    if node_radius > 0:
        nodes = pv.PolyData(Y).glyph(geom=pv.Sphere(radius=node_radius, theta_resolution=10, phi_resolution=10),
                                     scale=False, orient=False)
        line = line.merge(nodes).extract_surface(algorithm=None) if len(Y) > 1 else nodes
    if arrows is not None and len(arrows[0]) and arrow_size > 0:
        tips = pv.PolyData(np.asarray(arrows[0], np.float64))
        tips["direction"] = np.asarray(arrows[1], np.float64)
        # the cone's tip stands at the position: centred half a height back along the direction
        cone = pv.Cone(center=(-0.5 * arrow_size, 0.0, 0.0), direction=(1.0, 0.0, 0.0), height=arrow_size,
                       radius=0.4 * arrow_size, resolution=14)
        line = line.merge(tips.glyph(orient="direction", scale=False, geom=cone))
    return line


def add_trajectory(plotter, Y, color=ORIGINAL_COLOUR, *, line_width: float = 5.0, name: str = "trajectory",
                   markers=None, marker_radius: float = 0.0, arrow_size: float = 0.0) -> PolylineHandle:
    """A trajectory through ``Y`` (n, >=3) as a tube-rendered polyline.

    The paper draws the original trajectory black and the generated one red
    (:data:`ORIGINAL_COLOUR`, :data:`SYNTHETIC_COLOUR`). ``markers`` (indices into
    ``Y``, e.g. phone mid-points) are drawn as spheres of ``marker_radius``; with
    ``arrow_size`` > 0 cones show which way it runs (:func:`direction_arrows`).
    """
    mesh = pv.PolyData(np.zeros((1, 3), np.float32))
    actor = plotter.add_mesh(mesh, color=color, line_width=line_width, render_lines_as_tubes=True, name=name,
                             pickable=False, reset_camera=False, render=False)
    h = PolylineHandle(plotter, mesh, actor, arrow_size=arrow_size)
    h.update(Y)
    if markers is not None and marker_radius > 0 and len(h.points):
        idx = np.asarray(markers, dtype=int)
        idx = idx[(idx >= 0) & (idx < len(h.points))]
        glyphs = pv.PolyData(h.points[idx]).glyph(geom=pv.Sphere(radius=marker_radius), scale=False, orient=False)
        h.markers = Handle(plotter, glyphs, plotter.add_mesh(glyphs, color=color, name=f"{name}_markers",
                                                               pickable=False, reset_camera=False, render=False))
    return h


def add_state_path(plotter, centroids, path=None, *, color=PATH_COLOUR, node_radius: float = 0.0,
                   line_width: float = 5.0, name: str = "state_path", arrow_size: float = 0.0) -> PolylineHandle:
    """The minimum-distance state path as a polyline over state centroids.

    Parameters
    ----------
    centroids : ndarray of shape (K, >=3)
    path : sequence of int or None
        States along the path (None: hidden until ``handle.update(centroids[path])``).
    arrow_size : float
        Cones of this length show its direction (from the selected state to the target).
    """
    C = _xyz(centroids, "centroids")
    mesh = pv.PolyData(np.zeros((1, 3), np.float32))
    actor = plotter.add_mesh(mesh, color=color, line_width=line_width, render_lines_as_tubes=True, name=name,
                             pickable=False, reset_camera=False, render=False)
    h = PolylineHandle(plotter, mesh, actor, node_radius=node_radius, arrow_size=arrow_size)
    h.update(C[np.asarray(path, dtype=int)] if path is not None else None)
    return h


class EllipsoidHandle(Handle):
    """A cluster's ellipsoid: a translucent fill (``actor``) and an opaque outline (``outline``, its
    silhouette from the current camera, redrawn by VTK as the camera moves)."""

    def __init__(self, plotter, mesh, actor, outline):
        super().__init__(plotter, mesh, actor)
        self.outline = outline

    def set_visible(self, visible: bool) -> None:
        self.actor.SetVisibility(bool(visible))
        if self.outline is not None:
            self.outline.SetVisibility(bool(visible))

    def set_opacity(self, opacity: float) -> None:
        """The fill's opacity (0: the outline alone)."""
        self.actor.prop.opacity = float(opacity)
        self.actor.SetVisibility(self.visible_outline and opacity > 0)

    @property
    def visible_outline(self) -> bool:
        return self.outline is None or bool(self.outline.GetVisibility())

    @property
    def visible(self) -> bool:
        return bool(self.actor.GetVisibility()) or (self.outline is not None and bool(self.outline.GetVisibility()))

    def set_color(self, color) -> None:
        self.actor.prop.color = color
        if self.outline is not None:
            self.outline.prop.color = outline_colour(color)

    def remove(self) -> None:
        super().remove()
        if self.outline is not None:
            self.plotter.remove_actor(self.outline, render=False)


def outline_colour(color) -> tuple:
    """The outline of a filled shape of ``color``: the same hue, darker (reads on white and on the fill)."""
    return tuple(0.6 * float(c) for c in pv.Color(color).float_rgb)


def add_cluster_ellipsoids(plotter, vertices, faces, color, *, opacity: float = 0.3, outline_width: float = 2.5,
                           name: str = "ellipsoid") -> EllipsoidHandle:
    """A phone cluster's 2-s.d. ellipsoid from ``(vertices (M, 3), faces (F, 3))``: a translucent fill of
    ``opacity`` and an opaque outline of the same hue, darker (:func:`outline_colour`), so a cluster
    reads at a glance whatever the fill's opacity (``outline_width`` 0: none)."""
    V = _xyz(vertices, "ellipsoid vertices", 4)
    Fc = np.asarray(faces, dtype=np.int64)
    if Fc.ndim != 2 or Fc.shape[1] != 3 or (Fc.size and (Fc.min() < 0 or Fc.max() >= len(V))):
        raise ValueError(f"faces must be (F, 3) indices into {len(V)} vertices, got shape {Fc.shape}")
    mesh = pv.PolyData(V, np.hstack([np.full((len(Fc), 1), 3, np.int64), Fc]).ravel())
    # front faces only: a convex translucent surface then blends correctly in any draw order
    # (the explorer renders translucency without order-independent transparency, see make_plotter)
    actor = plotter.add_mesh(mesh, color=color, opacity=opacity, smooth_shading=True, name=name, pickable=False,
                             reset_camera=False, render=False, culling="back")
    outline = None
    if outline_width > 0:  # vtkPolyDataSilhouette follows the camera: the outline as seen, at every render
        from vtkmodules.vtkFiltersHybrid import vtkPolyDataSilhouette

        alg = vtkPolyDataSilhouette()
        alg.SetInputData(mesh)
        alg.SetCamera(plotter.renderer.GetActiveCamera())
        alg.SetEnableFeatureAngle(False)
        mapper = pv.DataSetMapper()
        mapper.SetInputConnection(alg.GetOutputPort())
        outline, prop = plotter.add_actor(mapper, reset_camera=False, name=f"{name}_outline", pickable=False,
                                          render=False)
        prop.color = outline_colour(color)
        prop.line_width = float(outline_width)
        outline._lipspace_silhouette = alg  # kept alive with the actor
    h = EllipsoidHandle(plotter, mesh, actor, outline)
    h.actor.SetVisibility(opacity > 0)
    return h


class MarkerHandle(Handle):
    """A sphere marking one point; :meth:`move` puts it elsewhere in place.

    The sphere is built once around the origin and moved by its actor's position, so
    following a playing trajectory costs no geometry rebuild.
    """

    def __init__(self, plotter, mesh, actor, radius):
        super().__init__(plotter, mesh, actor)
        self.radius = float(radius)
        self.center = None

    def move(self, center) -> None:
        self.center = _vec(center, "center")
        self.actor.SetPosition(*self.center)
        self.set_visible(True)


def add_marker(plotter, center=None, radius: float = 1.0, *, color=(1.0, 1.0, 0.0),
               name: str = "marker") -> MarkerHandle:
    """A sphere marking one point (the selected frame), hidden while ``center`` is None."""
    mesh = pv.Sphere(radius=radius, center=(0.0, 0.0, 0.0))
    actor = plotter.add_mesh(mesh, color=color, name=name, pickable=False, reset_camera=False, render=False)
    h = MarkerHandle(plotter, mesh, actor, radius)
    if center is None:
        h.set_visible(False)
    else:
        h.move(center)
    return h


def overlay_renderer(plotter):
    """A renderer layered over ``plotter``'s, sharing its camera: what it draws is never hidden.

    Created once per plotter (layer 1 of the render window, same viewport, its own
    light); the layer's depth buffer is cleared, so its actors are drawn over the point
    cloud while still hiding each other by depth. Picking stays on the main renderer.
    """
    ren = getattr(plotter, "_lipspace_overlay", None)
    if ren is not None:
        return ren
    from vtkmodules.vtkRenderingCore import vtkRenderer

    main = plotter.renderer
    win = plotter.render_window
    ren = vtkRenderer()
    ren.SetLayer(1)
    ren.SetViewport(*main.GetViewport())
    ren.SetActiveCamera(main.GetActiveCamera())
    ren.InteractiveOff()
    ren.SetPreserveDepthBuffer(False)
    win.SetNumberOfLayers(max(2, win.GetNumberOfLayers()))
    win.AddRenderer(ren)
    plotter._lipspace_overlay = ren
    return ren


def move_to_overlay(plotter, handle) -> None:
    """Draw ``handle`` (a Handle, a LocalFrameHandle or a PolylineHandle with markers) on top of the cloud."""
    ren = overlay_renderer(plotter)
    parts = handle.parts.values() if isinstance(handle, LocalFrameHandle) else [handle]
    for h in parts:
        plotter.renderer.RemoveActor(h.actor)
        ren.AddActor(h.actor)
