"""The manifold view: F^y in 3-D, coloured by density, class, phone, utterance or hop distance.

Shows the zero-velocity plane, the global S and V, the picked frame's local s_i,
v_i and normal, trajectories (original black, synthetic red), the minimum-distance
path between two states and phone cluster ellipsoids. A click selects the nearest
frame (and its state); with the *Path* box ticked, or with Shift held, a second
click sets the target state and draws the path between them.
"""
from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from app import scene
from app.picking import PointLocator, handle_pick
from app.state import COLOR_MODES, HEMISPHERES, point_colors
from app.views._common import (blocked, camera_of, close_plotter, connect_all,
                               disconnect_all, make_plotter, RenderScheduler, set_camera)

__all__ = ["ManifoldView", "axes_origin"]

COLOR_LABELS = {"density": "Density", "class": "Tangent class", "phone": "Phone", "utterance": "Utterance",
                "distance": "Hop distance"}
HEMI_LABELS = {"future": "Future hemisphere", "past": "Past hemisphere", "off": "No hemisphere"}


def axes_origin(Y, plane_point, S, V, length_scale) -> np.ndarray:
    """Where to root the global S and V arrows: on the zero-velocity plane, beside the cloud.

    S and V are directions; drawn from the plane point they vanish inside the points,
    so they start at the cloud's back edge along S, just outside it across the plane
    (like the axes glyph of the paper's Fig. 2a).
    """
    S = np.asarray(S, float) / np.linalg.norm(S)
    V = np.asarray(V, float) / np.linalg.norm(V)
    W = np.cross(V, S)
    d = np.asarray(Y, float)[:, :3] - plane_point
    return np.asarray(plane_point, float) + (d @ S).min() * S + ((d @ W).max() + 0.05 * length_scale) * W


class ManifoldView(QtWidgets.QWidget):
    """3-D view of the manifold bound to an :class:`app.state.AppState`."""

    #: clouds up to this many frames are drawn as shaded spheres, larger ones as flat dots
    SPHERE_POINTS_MAX = 10000

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.state = state
        self.handles: dict = {}
        self.ellipsoids: dict = {}
        self.members: dict = {}
        self.picker = None
        self.locator = None
        self.coloring = None
        self._legend_mode = None

        self.color_box = QtWidgets.QComboBox()
        for m in COLOR_MODES:
            self.color_box.addItem(COLOR_LABELS[m], m)
        self.color_box.setToolTip("Colour the points by")
        self.hemi_box = QtWidgets.QComboBox()
        for m in HEMISPHERES:
            self.hemi_box.addItem(HEMI_LABELS[m], m)
        self.hemi_box.setToolTip("Which hemisphere of the clicked state to colour by directed hop distance")
        self.path_box = QtWidgets.QCheckBox("Path")
        self.path_box.setToolTip("Tick (or hold Shift) and click a second point to draw the minimum-distance "
                                 "path between the two states")
        self.points_box = QtWidgets.QCheckBox("Points")
        self.points_box.setChecked(True)
        self.points_box.setToolTip("Show the frames (hide them to see trajectories and paths alone)")
        self.plane_box = QtWidgets.QCheckBox("Plane")
        self.plane_box.setChecked(True)
        self.plane_box.setToolTip("Show the zero-velocity plane")
        self.axes_box = QtWidgets.QCheckBox("S, V")
        self.axes_box.setChecked(True)
        self.axes_box.setToolTip("Show the global shape (S) and velocity (V) directions")
        self.clear_btn = QtWidgets.QPushButton("Clear")
        self.clear_btn.setToolTip("Clear the selection (Esc)")
        self.info = QtWidgets.QLabel("Click a point to select its state")

        bar = QtWidgets.QHBoxLayout()
        bar.setContentsMargins(4, 2, 4, 2)
        for w in (QtWidgets.QLabel("Colour:"), self.color_box, self.hemi_box, self.path_box, self.points_box,
                  self.plane_box, self.axes_box, self.clear_btn):
            bar.addWidget(w)
        bar.addStretch(1)
        self.plotter = make_plotter(self)
        self.renderer = RenderScheduler(self.plotter)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addLayout(bar)
        lay.addWidget(self.plotter.interactor, 1)
        lay.addWidget(self.info)

        self.color_box.currentIndexChanged.connect(lambda _: state.set_color_mode(self.color_box.currentData()))
        self.hemi_box.currentIndexChanged.connect(lambda _: state.set_hemisphere(self.hemi_box.currentData()))
        self.path_box.toggled.connect(state.set_path_mode)
        self.points_box.toggled.connect(self._show_points)
        self.plane_box.toggled.connect(lambda on: self._set_visible("plane", on))
        self.axes_box.toggled.connect(self._show_axes)
        self.clear_btn.clicked.connect(state.clear_selection)
        esc = QtGui.QShortcut(QtGui.QKeySequence(QtCore.Qt.Key.Key_Escape), self)
        esc.activated.connect(state.clear_selection)

        ev = state.events
        # one handler for everything one action changes: a click (frame, state, target, path,
        # colour mode) recolours at most once and asks for one render
        self._connections = [
            (ev.changed, self._on_changed),
            (ev.path_mode, lambda on: self._sync_box(self.path_box, on)),
        ]
        self.n_recolors = 0
        connect_all(self._connections)
        if state.manifold is not None:
            self.rebuild()

    # ------------------------------------------------------------------ build
    def rebuild(self) -> None:
        """Redraw everything for the state's manifold (after loading one)."""
        p = self.plotter
        if self.picker is not None:
            self.picker.remove()
        p.clear_actors()
        self.handles, self.ellipsoids, self.members = {}, {}, {}
        self._legend_mode = None
        m = self.state.manifold
        if m is None:
            self.renderer.request()
            return
        Y = np.asarray(m.Fy_[:, :3], dtype=np.float64)
        L = scene.scene_scale(Y)
        self.scale = L
        t = m.tangent_
        h = self.handles
        # shaded spheres cost ~4x flat dots per frame in software GL; at 3.5 px they are hardly
        # distinguishable, so large clouds (the default talker's 28,800 frames) use dots
        small = len(Y) <= self.SPHERE_POINTS_MAX
        h["points"] = scene.add_manifold_points(p, Y, point_size=5.0 if small else 3.5, spheres=small)
        h["plane"] = scene.add_zero_velocity_plane(p, t.plane_point_, t.plane_normal_, 1.1 * L)
        h["axes"] = scene.add_global_axes(p, axes_origin(Y, t.plane_point_, t.S_, t.plane_normal_, L), t.S_,
                                          t.plane_normal_, 0.45 * L)
        h["local"] = scene.add_local_frame(p, length=0.18 * L)
        h["marker"] = scene.add_marker(p, None, 0.018 * L, color=(1.0, 0.85, 0.0), name="selected")
        h["target"] = scene.add_marker(p, None, 0.018 * L, color=(0.0, 0.8, 0.8), name="target")
        h["path"] = scene.add_state_path(p, m.states_.centroids_[:, :3], None, node_radius=0.006 * L)
        h["original"] = scene.add_trajectory(p, None, scene.ORIGINAL_COLOUR, name="original")
        h["synthetic"] = scene.add_trajectory(p, None, scene.SYNTHETIC_COLOUR, name="synthetic")
        h["play_o"] = scene.add_marker(p, None, 0.016 * L, color=scene.ORIGINAL_COLOUR, name="play_original")
        h["play_s"] = scene.add_marker(p, None, 0.016 * L, color=scene.SYNTHETIC_COLOUR, name="play_synthetic")
        self._bar = self._make_scalar_bar()
        self.locator = PointLocator(Y)
        self.picker = scene.enable_click_picking(p, h["points"].actor, self._on_pick)
        self._set_visible("plane", self.plane_box.isChecked())
        self._show_points(self.points_box.isChecked())
        self._show_axes(self.axes_box.isChecked())
        with blocked(self.path_box):
            self.path_box.setChecked(self.state.path_mode)
        self._on_mode(render=False)
        self._on_selection(render=False, recolor=False)  # _on_mode has coloured the points
        self._on_path(render=False)
        self._on_trajectories(render=False)
        self._on_phones(render=False)
        p.renderer.ResetCamera(*h["points"].mesh.bounds)  # frame the cloud, not the plane (VTK's: no render)
        p.camera_set = True  # keep this framing (pyvista re-frames everything on first camera access otherwise)
        self.renderer.request()

    def _make_scalar_bar(self):
        import pyvista as pv
        from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor

        bar = vtkScalarBarActor()
        bar.SetLookupTable(pv.LookupTable(cmap="jet"))
        bar.SetOrientationToVertical()
        bar.SetPosition(0.88, 0.1)
        bar.SetWidth(0.07)
        bar.SetHeight(0.6)
        bar.SetNumberOfLabels(4)
        bar.UnconstrainedFontSizeOn()
        bar.SetVerticalTitleSeparation(6)
        for tp in (bar.GetLabelTextProperty(), bar.GetTitleTextProperty()):
            tp.SetColor(0.1, 0.1, 0.1)
            tp.SetShadow(False)
            tp.SetItalic(False)
            tp.SetFontSize(12)
            tp.SetBold(False)
        self.plotter.add_actor(bar, reset_camera=False, pickable=False, name="scalar_bar", render=False)
        return bar

    # --------------------------------------------------------------- events
    def _on_pick(self, point_id, xyz, shift):
        handle_pick(self.state, int(point_id), self.locator, as_target=True if shift else None)

    def _sync_box(self, box, on):
        with blocked(box):
            box.setChecked(bool(on))

    def _set_visible(self, key, on):
        if key in self.handles:
            self.handles[key].set_visible(on)
            self.renderer.request()

    def _show_points(self, on):
        if "points" in self.handles:
            self.handles["points"].set_visible(on)
            self._bar.SetVisibility(on and self.coloring is not None and self.coloring.cmap is not None)
            self.renderer.request()

    def _show_axes(self, on):
        axes = self.handles.get("axes")
        if axes:
            for k in ("S", "V"):
                axes[k].set_visible(on)
            if "labels" in axes:
                axes["labels"].SetVisibility(on)
            self.renderer.request()

    def _on_changed(self, names) -> None:
        """Bring the view up to date with one action's changed fields (``events.changed``)."""
        if "manifold" in names:
            self.rebuild()
            return
        if "points" not in self.handles:
            return
        s = self.state
        selection = bool(names & {"frame", "state", "target"})
        recolor = (bool(names & {"color_mode", "hemisphere"})
                   or (s.color_mode == "distance" and "state" in names)
                   or (s.color_mode == "utterance" and "utterance" in names))
        if names & {"color_mode", "hemisphere"}:
            self._sync_mode_boxes()
        if selection:
            self._on_selection(render=False, recolor=False)
        if "path" in names:
            self._on_path(render=False)
        if "trajectory" in names:
            self._on_trajectories(render=False)
        if "visible_phones" in names:
            self._on_phones(render=False)
        if recolor:
            self._recolor(render=False)
        elif selection or "path" in names:
            self._update_info()
        if names & {"playback", "playing"} and "trajectory" not in names:
            self._on_playback(render=False)
        if recolor or selection or names & {"path", "trajectory", "visible_phones"}:
            self.renderer.request()
        elif names & {"playback", "playing"}:
            self._request_playback_render()

    def _sync_mode_boxes(self):
        with blocked(self.color_box, self.hemi_box):
            self.color_box.setCurrentIndex(COLOR_MODES.index(self.state.color_mode))
            self.hemi_box.setCurrentIndex(HEMISPHERES.index(self.state.hemisphere))

    def _on_mode(self, render=True):
        self._sync_mode_boxes()
        self._recolor(render=render)

    def _recolor(self, render=True):
        if "points" not in self.handles:
            return
        c = point_colors(self.state.color_mode, self.state.manifold, self.state)
        self.n_recolors += 1
        self.coloring = c
        self.handles["points"].set_colors(c.rgb, c.values)
        bar = self._bar
        if c.cmap is not None:
            import pyvista as pv

            lut = pv.LookupTable(cmap=c.cmap)
            lut.scalar_range = c.clim
            bar.SetLookupTable(lut)
            bar.SetTitle(c.title)
            bar.SetVisibility(self.points_box.isChecked())
        else:
            bar.SetVisibility(False)
        want_legend = self.state.color_mode == "class"
        if want_legend != (self._legend_mode == "class"):
            if want_legend:
                self.plotter.add_legend([[name, col] for name, col in c.legend], bcolor="white", border=False,
                                        size=(0.2, 0.1), loc="lower left", face="circle")
            else:
                self.plotter.remove_legend(render=False)
            self._legend_mode = "class" if want_legend else None
        self._update_info()
        if render:
            self.renderer.request()

    def _on_selection(self, render=True, recolor=True):
        if "points" not in self.handles:
            return
        s, m, h = self.state, self.state.manifold, self.handles
        if s.frame is not None:
            i = s.frame
            t = m.tangent_
            y = m.Fy_[i, :3]
            h["marker"].move(y)
            h["local"].update(y, t.s_[i], t.v_[i], t.normal_[i])
        elif s.state is not None:
            h["marker"].move(m.states_.centroids_[s.state, :3])
            h["local"].set_visible(False)
        else:
            h["marker"].set_visible(False)
            h["local"].set_visible(False)
        if s.target is not None:
            h["target"].move(m.states_.centroids_[s.target, :3])
        else:
            h["target"].set_visible(False)
        if recolor and s.color_mode == "distance":
            self._recolor(render=False)
        self._update_info()
        if render:
            self.renderer.request()

    def _update_info(self):
        s, m = self.state, self.state.manifold
        parts = []
        if s.frame is not None:
            u = m.corpus_.utterances[int(m.corpus_.utterance_index[s.frame])]
            ph = s.phones[s.frame] or "—"
            cls = int(m.tangent_.classes_[s.frame])
            from app.state import CLASS_LABELS

            parts.append(f"frame {s.frame} ({u.id}, t={(s.frame - u.start) / m.corpus_.rate:.2f} s, phone {ph}, "
                         f"{CLASS_LABELS[cls] if cls >= 0 else 'no step'})")
        if s.state is not None:
            parts.append(f"state {s.state}")
            if self.coloring is not None and self.coloring.values is not None and s.color_mode == "distance":
                v = self.coloring.values
                parts.append(f"{s.hemisphere}: {int(np.isfinite(v).sum())}/{len(v)} frames reachable")
        if s.target is not None:
            parts.append(f"target {s.target}: " + (f"{len(s.path) - 1} hops" if s.path is not None
                                                  else "unreachable"))
        self.info.setText("; ".join(parts) if parts else "Click a point to select its state "
                          "(Shift-click or tick Path for a path to a second state)")

    def _on_path(self, render=True):
        if "path" not in self.handles:
            return
        p = self.state.path
        C = self.state.manifold.states_.centroids_[:, :3]
        self.handles["path"].update(C[p] if p is not None else None)
        self._update_info()
        if render:
            self.renderer.request()

    def _on_trajectories(self, render=True):
        if "original" not in self.handles:
            return
        for key in ("original", "synthetic"):
            traj = getattr(self.state, key)
            self.handles[key].update(None if traj is None else np.asarray(traj.Y)[:, :3])
        self._on_playback(render=False)
        if render:
            self.renderer.request()

    #: while playing, the manifold view renders the moving markers at most this often, and at most
    #: PLAYBACK_RENDER_SHARE of the time (its last render's duration sets a longer interval on a slow
    #: or busy machine): the lip view gets the frame budget (a manifold frame costs several lip frames
    #: in software GL)
    PLAYBACK_RENDER_INTERVAL_S = 0.5
    PLAYBACK_RENDER_SHARE = 0.1

    def _on_playback(self, render=True):
        """Move the playback markers (actor positions only: the cloud is never recoloured)."""
        if "play_o" not in self.handles:
            return
        k = self.state.playback
        for key, traj in (("play_o", self.state.original), ("play_s", self.state.synthetic)):
            if k is None or traj is None:
                self.handles[key].set_visible(False)
            else:
                self.handles[key].move(np.asarray(traj.Y)[min(k, len(traj) - 1), :3])
        if render:
            self._request_playback_render()

    def _request_playback_render(self):
        """A render for moved playback markers: throttled while playing, at once otherwise."""
        wait = 0.0
        if self.state.playing:
            wait = max(self.PLAYBACK_RENDER_INTERVAL_S, self.renderer.last_duration / self.PLAYBACK_RENDER_SHARE)
        self.renderer.request(min_interval_s=wait)

    def _on_phones(self, render=True):
        if "points" not in self.handles:
            return
        from app.state import ellipsoid_colors

        want = self.state.visible_phones
        colours = ellipsoid_colors(want)
        Y = self.state.manifold.Fy_
        for ph in sorted(want - set(self.ellipsoids)):
            verts, faces = self.state.clusters.ellipsoid(ph)
            self.ellipsoids[ph] = scene.add_cluster_ellipsoids(self.plotter, np.asarray(verts)[:, :3], faces,
                                                               colours[ph], name=f"ellipsoid_{ph}")
            self.members[ph] = scene.add_point_markers(self.plotter, Y[self.state.clusters.members(ph), :3],
                                                       colours[ph], point_size=7, name=f"members_{ph}")
        for ph in self.ellipsoids:
            on = ph in want
            self.ellipsoids[ph].set_visible(on)
            self.members[ph].set_visible(on)
            if on:
                self.ellipsoids[ph].actor.prop.color = colours[ph]
                self.members[ph].actor.prop.color = colours[ph]
        if render:
            self.renderer.request()

    # ---------------------------------------------------------------- misc
    def camera(self) -> list:
        return camera_of(self.plotter)

    def set_camera(self, cam) -> None:
        set_camera(self.plotter, cam)

    def close_view(self) -> None:
        disconnect_all(self._connections)
        if self.picker is not None:
            self.picker.remove()
        self.renderer.stop()
        close_plotter(self.plotter)
