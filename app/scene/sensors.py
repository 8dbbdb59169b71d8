"""Sensors drawn as sensors in a 3-D view, as :class:`app.models.lip_drawing.LipDrawing` says.

After articulograph viewers (VisArtico, mview): each sensor a sphere (lip sensors in the
lips' colour, jaw, reference and tongue sensors grey) labelled with its name, the lip sensors
joined by straight lines in their order round the mouth, and the lip aperture a line of its
own from the upper- to the lower-lip sensors, labelled with its length in mm. A profile of
2-D midsagittal data shows which way the face looks (an arrow marked "front"). Nothing
between the sensors is interpolated: no contour, no surface. A measured surface (a mesh) is
drawn by :func:`app.scene.lips.add_lips`, which adds the aperture over it with
:class:`SensorsHandle` too.

Every label is a point of one label set whose text is updated with the frame (the aperture's
value), placed beside its sensor away from the sensors' centre so that labels do not stand
on the markers, and always placed (never hidden where two would touch).
"""
from __future__ import annotations

import numpy as np
import pyvista as pv

__all__ = ["SensorsHandle", "add_sensors", "as_points", "OTHER_COLOUR", "APERTURE_COLOUR"]

#: jaw, reference and tongue sensors
OTHER_COLOUR = (0.55, 0.55, 0.58)
#: the aperture's line and value
APERTURE_COLOUR = (0.15, 0.15, 0.18)
#: the unit of the labels' spacing: this fraction of the sensors' extent
LABEL_OFFSET = 0.14
#: a label's text starts this many units from its sensor, running away from it
GAP = 0.9


def as_points(points) -> np.ndarray:
    """One frame as a fresh float32 array (V, 3) (a flat frame of 3V values too); meshes never share the caller's
    memory."""
    P = np.array(points, dtype=np.float32)
    if P.ndim == 1:
        if P.size % 3:
            raise ValueError(f"a flat frame must hold 3 coordinates per point, got {P.size} values")
        P = P.reshape(-1, 3)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) == 0:
        raise ValueError(f"lip points must have shape (V, 3) with V > 0, got {P.shape}")
    return P


def _label_directions(ref, which, reach) -> list:
    """For each labelled point of ``which`` (indices into ``ref`` (V, 2), the reference frame in view x-y), the
    offset of its label in units of ``reach``: away from the points' centre, turned (30, 60, 90 degrees either
    way, then back) and moved out (1, then 1.7 reach) until it keeps ``2 * reach`` from the labels placed before
    it and ``0.8 * reach`` from every other point, so that no two labels stand on each other (JAW and LL of a
    Haskins recording)."""
    ref = np.asarray(ref, np.float64)[:, :2]
    centre = ref.mean(axis=0)
    placed, out = [], []
    for i in which:
        d0 = ref[i] - centre
        n = float(np.linalg.norm(d0))
        base = np.arctan2(d0[1], d0[0]) if n > 1e-9 * max(reach, 1e-12) else np.pi / 2
        choice = None
        for dist in (1.0, 1.7):
            for turn in (0, 30, -30, 60, -60, 90, -90, 135, -135, 180):
                a = base + np.radians(turn)
                d = dist * np.array([np.cos(a), np.sin(a)])
                anchor = ref[i] + d * reach
                far_from_labels = all(np.linalg.norm(anchor - q) >= 2.0 * reach for q in placed)
                far_from_points = all(np.linalg.norm(anchor - ref[j]) >= 0.8 * reach
                                      for j in range(len(ref)) if j != i)
                if far_from_labels and far_from_points:
                    choice = d
                    break
            if choice is not None:
                break
        if choice is None:
            a = base
            choice = np.array([np.cos(a), np.sin(a)])
        placed.append(ref[i] + choice * reach)
        out.append(choice)
    return out


def _justification(d) -> tuple[str, str]:
    """How a label in direction ``d`` from its sensor is justified at its anchor, so its text runs away from it."""
    if abs(d[0]) >= 0.5 * float(np.hypot(*d)):
        return ("left" if d[0] > 0 else "right"), "center"
    return "center", ("bottom" if d[1] > 0 else "top")


def _lines(points, pairs) -> pv.PolyData:
    """A PolyData of straight lines between ``pairs`` (E, 2) of ``points`` (V, 3) (no lines: points only)."""
    mesh = pv.PolyData(np.asarray(points, np.float32))
    if len(pairs):
        mesh.lines = np.hstack([np.full((len(pairs), 1), 2, np.int64), np.asarray(pairs, np.int64)]).ravel()
    return mesh


class SensorsHandle:
    """The actors of one frame's sensors, moved frame by frame (:meth:`update`).

    Attributes
    ----------
    drawing : app.models.lip_drawing.LipDrawing
    offset : ndarray (3,)
        Added to every frame (two trajectories side by side).
    markers, segments, aperture_line : pyvista.PolyData or None
    actor : vtk actor
        The lip sensors' spheres (the handle's colour).
    actors : list of vtk actors
        Everything drawn.
    label_texts : list of str
        The labels as drawn now (the sensors' names, the aperture's value, "front").
    label_anchors : ndarray (len(label_texts), 3)
        Where each label's text starts (it runs away from what it names).
    label_actors : list of vtk actors
        One label set per justification.
    aperture_value : float or None
        The drawn frame's aperture in the corpus's unit.
    """

    def __init__(self, plotter, drawing, points, *, color=(0.85, 0.45, 0.45), offset=(0.0, 0.0, 0.0),
                 point_size: float = 14.0, name: str = "sensors", labels: bool = True, markers: bool = True):
        self.plotter, self.drawing = plotter, drawing
        self.offset = np.asarray(offset, np.float32)
        self.name = name
        P = as_points(points)
        self._n = len(P)
        ref = P[:, :2]
        self._centre = ref.mean(axis=0)
        self._reach = LABEL_OFFSET * max(float(np.ptp(ref, axis=0).max()), 1e-6)
        self.actors, self.markers, self.segments, self.aperture_line = [], None, None, None
        self.actor = None
        Q = P + self.offset
        lip = np.asarray(drawing.lip, bool) if markers else np.zeros(self._n, bool)
        if markers and lip.any():
            self.markers = pv.PolyData(Q[lip])
            self.actor = plotter.add_mesh(self.markers, color=color, point_size=point_size,
                                          render_points_as_spheres=True, name=f"{name}_lip", pickable=False,
                                          reset_camera=False, render=False)
            self.actors.append(self.actor)
        self._other = None
        if markers and (~np.asarray(drawing.lip, bool)).any():
            self._other = pv.PolyData(Q[~np.asarray(drawing.lip, bool)])
            self.actors.append(plotter.add_mesh(self._other, color=OTHER_COLOUR, point_size=0.8 * point_size,
                                                render_points_as_spheres=True, name=f"{name}_other",
                                                pickable=False, reset_camera=False, render=False))
        if len(drawing.segments):
            self.segments = _lines(Q, drawing.segments)
            dark = tuple(0.6 * np.asarray(pv.Color(color).float_rgb))
            self.segment_actor = plotter.add_mesh(self.segments, color=dark, line_width=3.0, name=f"{name}_segments",
                                                  pickable=False, reset_camera=False, render=False)
            self.actors.append(self.segment_actor)
        if drawing.has_aperture:
            self.aperture_line = _lines(np.zeros((2, 3), np.float32), [(0, 1)])
            self.actors.append(plotter.add_mesh(self.aperture_line, color=APERTURE_COLOUR, line_width=1.5,
                                                name=f"{name}_aperture", pickable=False, reset_camera=False,
                                                render=False))
        self._label_of = [i for i, t in enumerate(drawing.labels) if t] if labels else []
        self._dirs = _label_directions(ref, self._label_of, self._reach)
        self._front = labels and drawing.view == "profile" and drawing.forward is not None
        if self._front:
            self._arrow = pv.Arrow(start=(0, 0, 0), direction=(float(drawing.forward[0]), float(drawing.forward[1]), 0),
                                   scale=2.0 * self._reach, tip_length=0.3, tip_radius=0.12, shaft_radius=0.04)
            self._arrow_base = np.asarray(self._arrow.points, np.float32).copy()
            self.actors.append(plotter.add_mesh(self._arrow, color=(0.3, 0.3, 0.3), name=f"{name}_front",
                                                pickable=False, reset_camera=False, render=False))
        # each label's text runs away from what it names (justified at its anchor): never over its sensor
        self.label_texts = [str(drawing.labels[i]) for i in self._label_of]
        self._justify = [_justification(d) for d in self._dirs]
        if drawing.has_aperture:
            self.label_texts.append("")
            self._justify.append(self._aperture_side(P))
        if self._front:
            self.label_texts.append("front")
            self._justify.append(("center", "bottom"))
        self.label_anchors = np.zeros((len(self.label_texts), 3), np.float32)
        self._label_sets = []  # (polydata, actor, label indices), one per justification
        for just in dict.fromkeys(self._justify):
            which = [k for k, j in enumerate(self._justify) if j == just]
            pts = pv.PolyData(np.zeros((len(which), 3), np.float32))
            arr = pv.convert_string_array(np.asarray([self.label_texts[k] for k in which], dtype=str))
            arr.SetName("sensor_labels")
            pts.GetPointData().AddArray(arr)
            actor = plotter.add_point_labels(pts, "sensor_labels", font_size=13, point_size=1, show_points=False,
                                             shape_opacity=0.0, shape=None, text_color=(0.1, 0.1, 0.1),
                                             always_visible=True, name=f"{name}_labels_{just[0]}_{just[1]}",
                                             justification_horizontal=just[0], justification_vertical=just[1],
                                             render=False, reset_camera=False)
            actor.GetMapper().PlaceAllLabelsOn()  # never hidden where two labels would touch
            self._label_sets.append((pts, actor, which))
            self.actors.append(actor)
        self.aperture_value = None
        self.update(P)

    # ------------------------------------------------------------------ per frame
    def update(self, points) -> None:
        P = as_points(points)
        if P.shape[0] != self._n:
            raise ValueError(f"frame has {P.shape[0]} points, the sensors are {self._n}")
        Q = P + self.offset
        lip = np.asarray(self.drawing.lip, bool)
        if self.markers is not None:
            self.markers.points[:] = Q[lip]
            self.markers.Modified()
        if self._other is not None:
            self._other.points[:] = Q[~lip]
            self._other.Modified()
        if self.segments is not None:
            self.segments.points[:] = Q
            self.segments.Modified()
        anchors = []
        for i, d in zip(self._label_of, self._dirs):
            anchors.append(np.asarray(Q[i], np.float32) + np.array([d[0], d[1], 0.0], np.float32) * GAP * self._reach)
        if self.drawing.has_aperture:
            top, bottom, value = self.drawing.aperture(P)
            self.aperture_value = value
            self.aperture_line.points[:] = np.stack([top, bottom]) + self.offset
            self.aperture_line.Modified()
            anchors.append(self._aperture_anchor(P, top, bottom) + self.offset)
            self.label_texts[len(self._label_of)] = self.drawing.aperture_text(value)
        if self._front:
            lo, hi = P.min(axis=0), P.max(axis=0)
            base = np.array([hi[0] + self._reach, hi[1] + self._reach, 0.5 * (lo[2] + hi[2])], np.float32)
            self._arrow.points[:] = self._arrow_base + base + self.offset
            self._arrow.Modified()
            anchors.append(base + self.offset + np.array([self._reach, 0.25 * self._reach, 0.0], np.float32))
        if anchors:
            self.label_anchors = np.asarray(anchors, np.float32)
        for pts, _actor, which in self._label_sets:
            pts.points[:] = self.label_anchors[which]
            arr = pts.GetPointData().GetAbstractArray("sensor_labels")
            for j, k in enumerate(which):
                arr.SetValue(j, self.label_texts[k])
            arr.Modified()
            pts.Modified()

    def _aperture_side(self, P):
        """The aperture value's justification: beside the line (on a side no other sensor lies on), else under."""
        top, bottom, _ = self.drawing.aperture(P)
        side = self._free_side(P, top, bottom)
        return ("left", "center") if side > 0 else ("right", "center") if side < 0 else ("center", "top")

    def _free_side(self, P, top, bottom) -> int:
        """+1 / -1: the side of the aperture line (view x) no other sensor lies on; 0: none (or a surface)."""
        mid = 0.5 * (top + bottom)
        rest = np.setdiff1d(np.arange(len(P)), np.r_[self.drawing.upper, self.drawing.lower])
        if self.drawing.kind != "sensors" or not len(rest):
            return 0 if self.drawing.kind != "sensors" else 1
        span = max(float(np.linalg.norm(top - bottom)), 1e-9)
        off = P[rest, 0] - mid[0]
        off = off[np.abs(off) > 0.05 * span]
        if np.any(off > 0) and np.any(off < 0):
            return 0
        return -1 if np.any(off > 0) else 1

    def _aperture_anchor(self, P, top, bottom):
        """The aperture value's anchor: beside the line's middle on the free side, else under the lowest sensor
        and its label."""
        mid = 0.5 * (top + bottom)
        side = self._free_side(P, top, bottom)
        if side:
            return (mid + np.array([side * GAP * self._reach, 0.0, 0.0])).astype(np.float32)
        below = 2.2 if self._label_of else GAP  # under the lowest sensor's own label, where there is one
        return np.array([mid[0], P[:, 1].min() - below * self._reach, mid[2]], np.float32)

    # ------------------------------------------------------------------ handle
    @property
    def points(self) -> np.ndarray:
        lip = np.asarray(self.drawing.lip, bool)
        out = np.zeros((self._n, 3), np.float32)
        if self.markers is not None:
            out[lip] = np.asarray(self.markers.points) - self.offset
        if self._other is not None:
            out[~lip] = np.asarray(self._other.points) - self.offset
        return out

    @property
    def visible(self) -> bool:
        return bool(self.actors and self.actors[0].GetVisibility())

    def set_visible(self, visible: bool) -> None:
        for a in self.actors:
            a.SetVisibility(bool(visible))

    @property
    def label_actors(self) -> list:
        return [actor for _pts, actor, _which in self._label_sets]

    def set_colour(self, color) -> None:
        """The lip sensors' colour (their lines a darker shade)."""
        rgb = pv.Color(color).float_rgb
        if self.actor is not None:
            self.actor.prop.color = rgb
        if self.segments is not None:
            self.segment_actor.prop.color = tuple(0.6 * np.asarray(rgb))

    def remove(self) -> None:
        for a in self.actors:
            self.plotter.remove_actor(a, render=False)
        self.actors = []


def add_sensors(plotter, drawing, points, **kwargs) -> SensorsHandle:
    """Draw one frame's sensors as ``drawing`` says (see :class:`SensorsHandle`); returns the handle."""
    return SensorsHandle(plotter, drawing, points, **kwargs)
