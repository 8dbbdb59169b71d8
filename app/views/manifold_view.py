"""The manifold view: F^y in 3-D, coloured by density, class, phone, utterance or hop distance.

Shows the zero-velocity plane, the global S and V, the picked frame's local s_i,
v_i and normal, trajectories (original black, synthetic red), the minimum-distance
path between two states and phone cluster ellipsoids. A click selects the nearest
frame (and its state); with the *Path* box ticked, or with Shift held, a second
click sets the target state and draws the path between them. The selection, target,
path, trajectories and playback markers are drawn over the cloud (a second renderer
layer). Hop distance is shown within a time horizon (slider, ms); the pointer's frame
is read out as it moves; Side / Top / Reset give the standard views; Esc resets the view.
"""
from __future__ import annotations

import time

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from app import scene
from app.models.colouring import CLASS_LABELS, ellipsoid_colors, point_colors
from app.models.picking import CloudLocator, handle_pick, hover_text
from app.models.state import COLOR_MODES, HEMISPHERES
from app.scene import legend as scene_legend
from app.scene.colour_bar import add_scalar_bar, configure_scalar_bar
from app.scene.projection import project, standard_camera, view_transform
from app.views._common import (
    RenderScheduler,
    blocked,
    camera_of,
    close_plotter,
    connect_all,
    disconnect_all,
    make_plotter,
    reserve_lines,
    set_camera,
    set_readout,
)
from app.views.flow_layout import FlowLayout

__all__ = ["ManifoldView", "axes_origin"]

COLOR_LABELS = {"density": "Density", "class": "Tangent class", "phone": "Phone", "utterance": "Utterance",
                "distance": "Hop distance"}
HEMI_LABELS = {"future": "Future hemisphere", "past": "Past hemisphere", "both": "Past and future",
               "off": "No hemisphere"}
#: the horizon slider runs 0..HORIZON_SLIDER_MS in whole frame periods; the "Horizon" box off means no horizon
HORIZON_SLIDER_MS = 500


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
    """3-D view of the manifold bound to an :class:`app.models.state.AppState`."""

    #: clouds (and a cluster's member markers) up to this many points are drawn as shaded spheres,
    #: larger ones as flat dots: 12,759 members of a phone at 1M frames took 50-70 ms of a 75-ms render
    #: as spheres
    SPHERE_POINTS_MAX = 10000

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.state = state
        self._play_started = 0.0  # perf_counter() when playback last started
        self.handles: dict = {}
        self.ellipsoids: dict = {}
        self.members: dict = {}
        self.picker = None
        self.locator = None
        self.coloring = None
        self._legend_mode = None
        self.legend = None  # the phone legend's vtkLegendBoxActor while one is shown

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
        self.clear_btn.setToolTip("Clear the selection and reset colours, horizon and readouts (Esc)")
        self.horizon_box = QtWidgets.QCheckBox("Horizon")
        self.horizon_box.setChecked(True)
        self.horizon_box.setToolTip("Colour only the states reachable within the time horizon (untick: every "
                                    "reachable state)")
        self.horizon_slider = QtWidgets.QSlider(QtCore.Qt.Orientation.Horizontal)
        self.horizon_slider.setMinimumWidth(90)
        self.horizon_slider.setToolTip("Time horizon of the hemisphere in ms: states more hops away than fit in "
                                       "this time at the corpus frame rate are dimmed")
        self.horizon_label = QtWidgets.QLabel("")
        self.phone_edit = QtWidgets.QLineEdit()
        self.phone_edit.setPlaceholderText("all phones: type e.g. p b m")
        self.phone_edit.setMaximumWidth(170)
        self.phone_edit.setToolTip("Phones to colour, separated by spaces (e.g. 'p b m'); the others are dimmed. "
                                   "Empty: all phones")
        self.view_btns = {}
        for key, label, tip in (("side", "Side", "The S–V plane face on: opening half above the zero-velocity "
                                 "plane, closing half below"),
                                ("top", "Top", "Looking down V onto the zero-velocity plane"),
                                ("default", "Reset", "The default view: both halves, the plane slightly from "
                                 "above")):
            b = QtWidgets.QToolButton()
            b.setText(label)
            b.setToolTip(tip)
            b.clicked.connect(lambda _=False, k=key: self.standard_view(k))
            self.view_btns[key] = b
        self.info = QtWidgets.QLabel("Click a point to select its state")
        self.hover_label = QtWidgets.QLabel("")
        self.hover_label.setStyleSheet("color: #444")

        # controls in groups that wrap to a new row in a narrow window (FlowLayout): the view's minimum
        # width is that of its widest group, not of every control side by side
        bar = FlowLayout(spacing=10)
        for group in ((QtWidgets.QLabel("Colour:"), self.color_box, self.phone_edit),
                      (self.hemi_box, self.horizon_box, self.horizon_slider, self.horizon_label),
                      (self.path_box, self.points_box, self.plane_box, self.axes_box),
                      (*self.view_btns.values(), self.clear_btn)):
            box = QtWidgets.QWidget()
            row = QtWidgets.QHBoxLayout(box)
            row.setContentsMargins(0, 0, 0, 0)
            row.setSpacing(4)
            for w in group:
                row.addWidget(w)
            bar.addWidget(box)
        for label in (self.info, self.hover_label):  # long readouts wrap instead of widening the view
            label.setWordWrap(True)
            reserve_lines(label, 2)  # and keep their height (set_readout): the 3-D view above keeps its size
        self.plotter = make_plotter(self)
        self.renderer = RenderScheduler(self.plotter)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addLayout(bar)
        lay.addWidget(self.plotter.interactor, 1)
        lay.addWidget(self.info)
        lay.addWidget(self.hover_label)

        self.color_box.currentIndexChanged.connect(lambda _: state.set_color_mode(self.color_box.currentData()))
        self.hemi_box.currentIndexChanged.connect(lambda _: state.set_hemisphere(self.hemi_box.currentData()))
        self.path_box.toggled.connect(state.set_path_mode)
        self.points_box.toggled.connect(self._show_points)
        self.plane_box.toggled.connect(lambda on: self._set_visible("plane", on))
        self.axes_box.toggled.connect(self._show_axes)
        self.clear_btn.clicked.connect(state.reset_view)
        self.esc_shortcut = QtGui.QShortcut(QtGui.QKeySequence(QtCore.Qt.Key.Key_Escape), self)
        self.esc_shortcut.activated.connect(state.reset_view)
        self.horizon_box.toggled.connect(lambda _on: self._push_horizon())
        self.horizon_slider.valueChanged.connect(lambda _v: self._push_horizon())
        self.phone_edit.editingFinished.connect(self._push_phone_filter)
        # hover: the latest pointer position is looked up at most every HOVER_INTERVAL_MS
        self._hover_pos = None
        self._hover_xy = None
        self._hover_timer = QtCore.QTimer(self)
        self._hover_timer.setSingleShot(True)
        self._hover_timer.setInterval(self.HOVER_INTERVAL_MS)
        self._hover_timer.timeout.connect(self._do_hover)
        self._hover_observer = None

        ev = state.events
        # one handler for everything one action changes: a click (frame, state, target, path,
        # colour mode) recolours at most once and asks for one render
        self._connections = [
            (ev.changed, self._on_changed),
            (ev.path_mode, lambda on: self._sync_box(self.path_box, on)),
        ]
        self.n_recolors = 0
        connect_all(self._connections)
        self._sync_horizon()
        if state.manifold is not None:
            self.rebuild()

    # ------------------------------------------------------------------ build
    def rebuild(self) -> None:
        """Redraw everything for the state's manifold (after loading one)."""
        p = self.plotter
        if self.picker is not None:
            self.picker.remove()
        p.clear_actors()
        scene.overlay_renderer(p).RemoveAllViewProps()
        self.handles, self.ellipsoids, self.members = {}, {}, {}
        self._legend_mode, self.legend = None, None  # cleared with the other actors
        m = self.state.manifold
        if m is None:
            self.renderer.request()
            return
        cloud = self.state.cloud  # level of detail: every frame, or one point per group of frames (app.models.lod)
        Y = np.asarray(m.Fy_[cloud.frames, :3], dtype=np.float64)  # the drawn points
        L = scene.scene_scale(cloud.bounds)
        self.scale = L
        t = m.tangent_
        h = self.handles
        # shaded spheres cost ~4x flat dots per frame in software GL; at 3.5 px they are hardly
        # distinguishable, so large clouds (the default talker's 28,800 frames) use dots
        small = len(Y) <= self.SPHERE_POINTS_MAX
        size = 5.0 if small else 3.5
        h["points"] = scene.add_manifold_points(p, m.Fy_, point_size=size, spheres=small,
                                                frames=None if cloud.whole else cloud.frames)
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
        for key in self.OVERLAY:  # drawn over the cloud: never buried inside it
            scene.move_to_overlay(p, h[key])
        self._bar = add_scalar_bar(p)
        # a click or the pointer finds its frame among every frame, drawn or not
        self.locator = CloudLocator(m.Fy_, cloud, dot_radius=0.5 * size)
        self.picker = scene.enable_click_picking(p, h["points"].actor, self._on_pick, locate=self.frame_at)
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
        self._install_hover()
        self.standard_view("default", render=False)
        p.camera_set = True  # keep this framing (pyvista re-frames everything on first camera access otherwise)
        self.renderer.request()

    #: handles drawn in the overlay layer, over the cloud
    OVERLAY = ("marker", "target", "path", "local", "original", "synthetic", "play_o", "play_s")
    #: milliseconds between two hover look-ups while the pointer moves
    HOVER_INTERVAL_MS = 60

    def standard_view(self, name: str, render: bool = True) -> None:
        """Put the camera in a standard view: "side" (S–V plane), "top" (down V) or "default"."""
        m = self.state.manifold
        if m is None or "points" not in self.handles:
            return
        t = m.tangent_
        # the cloud's bounds stand for every frame (the camera only reads their extent)
        pos, focal, up = standard_camera(name, self.state.cloud.bounds, t.plane_point_, t.S_, t.plane_normal_)
        cam = self.plotter.renderer.GetActiveCamera()
        cam.SetPosition(*pos)
        cam.SetFocalPoint(*focal)
        cam.SetViewUp(*up)
        ren = self.plotter.renderer
        lo, hi = np.reshape(self.handles["points"].mesh.bounds, (3, 2)).T
        tips = self.handles["axes"].get("tips") if isinstance(self.handles.get("axes"), dict) else None
        if tips is not None:  # the S and V labels stand beyond the cloud: frame them too
            lo, hi = np.minimum(lo, tips.min(axis=0)), np.maximum(hi, tips.max(axis=0))
        ren.ResetCamera(*np.column_stack([lo, hi]).ravel())  # fit the cloud and the labels, same direction
        if tips is not None:  # and keep the labels' text inside the view, not cut at its edge
            for _ in range(2):
                M, size = view_transform(self.plotter)
                z = scene.label_zoom(project(tips, M, size)[0], size)
                if z >= 0.999:
                    break
                cam.Zoom(z)
        ren.ResetCameraClippingRange()
        if render:
            self.renderer.request()

    # ---------------------------------------------------------------- hover
    def _install_hover(self):
        iren = getattr(self.plotter, "iren", None)
        if self._hover_observer is None and iren is not None and getattr(iren, "interactor", None) is not None:
            self._hover_observer = iren.add_observer("MouseMoveEvent", self._on_mouse_move)

    def _on_mouse_move(self, _obj, _event):
        iren = self.plotter.iren.interactor
        self._hover_pos = tuple(iren.GetEventPosition())
        if not self._hover_timer.isActive():
            self._hover_timer.start()

    def _do_hover(self):
        if self._hover_pos is None or self.state.manifold is None or "points" not in self.handles:
            return
        self.state.set_hover(self.hover_frame(self._hover_pos))

    def hover_frame(self, display_xy, radius: float = 6.0):
        """The frame under display position ``display_xy`` (pixels, origin bottom left), or None."""
        if not self.handles["points"].visible:
            return None
        return self.frame_at(display_xy, radius=radius)

    def frame_at(self, display_xy, radius: float | None = None):
        """The frame a click at ``display_xy`` selects, among every frame (:class:`app.models.picking.CloudLocator`)."""
        if self.locator is None:
            return None
        M, size = view_transform(self.plotter)
        return self.locator.locate(display_xy, M, size, radius=radius)

    # --------------------------------------------------------------- events
    def _on_pick(self, frame, _xyz, shift):
        handle_pick(self.state, frame, as_target=True if shift else None)

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
            self._sync_horizon()
            self._sync_phone_edit()
            self.rebuild()
            return
        if names & {"hover"}:
            self._update_hover()
        if "points" not in self.handles:
            return
        s = self.state
        selection = bool(names & {"frame", "state", "target"})
        recolor = (bool(names & {"color_mode", "hemisphere", "visible_phones"})
                   or (s.color_mode == "distance" and bool(names & {"state", "horizon_ms"}))
                   or (s.color_mode == "phone" and "phone_filter" in names)
                   or (s.color_mode == "utterance" and "utterance" in names))
        if names & {"color_mode", "hemisphere"}:
            self._sync_mode_boxes()
        if "horizon_ms" in names:
            self._sync_horizon()
        if "phone_filter" in names:
            self._sync_phone_edit()
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
        if recolor or selection or names & {"path", "trajectory", "visible_phones", "horizon_ms", "phone_filter"}:
            self.renderer.request()
        elif names & {"playback", "playing"}:
            if "playing" in names and self.state.playing:
                self._play_started = time.perf_counter()
            self._request_playback_render()

    def _sync_mode_boxes(self):
        with blocked(self.color_box, self.hemi_box):
            self.color_box.setCurrentIndex(COLOR_MODES.index(self.state.color_mode))
            self.hemi_box.setCurrentIndex(HEMISPHERES.index(self.state.hemisphere))
        self.phone_edit.setEnabled(self.state.color_mode == "phone")

    def _frame_ms(self) -> float:
        m = self.state.manifold
        return 1000.0 / float(m.corpus_.rate) if m is not None else 1000.0 / 60.0

    def _push_horizon(self):
        """The slider moves in whole frame periods (one hop each); the state holds milliseconds."""
        ms = self.horizon_slider.value() * self._frame_ms() if self.horizon_box.isChecked() else None
        self.state.set_horizon(ms)

    def _sync_horizon(self):
        """Slider, box and label from the state's horizon (ms, and hops at the corpus rate)."""
        from engine.graph.hemispheres import horizon_hops

        ms = self.state.horizon_ms
        m = self.state.manifold
        step = self._frame_ms()
        with blocked(self.horizon_box, self.horizon_slider):
            self.horizon_box.setChecked(ms is not None)
            self.horizon_slider.setRange(0, int(HORIZON_SLIDER_MS // step))  # positions = frame periods = hops
            if ms is not None:
                self.horizon_slider.setValue(int(np.floor(min(ms, HORIZON_SLIDER_MS) / step + 1e-9)))
        self.horizon_slider.setEnabled(ms is not None)
        if ms is None:
            self.horizon_label.setText("all hops")
        elif m is None:
            self.horizon_label.setText(f"{ms:.0f} ms")
        else:
            H = horizon_hops(ms / 1000.0, m.corpus_.rate)
            self.horizon_label.setText(f"{ms:.0f} ms = {H} hop{'s' if H != 1 else ''}")

    def _push_phone_filter(self):
        words = self.phone_edit.text().replace(",", " ").split()
        try:
            self.state.set_phone_filter(words)
        except ValueError as exc:
            QtWidgets.QMessageBox.warning(self, "Lipspace", str(exc))
            self._sync_phone_edit()

    def _sync_phone_edit(self):
        text = " ".join(sorted(self.state.phone_filter))
        if self.phone_edit.text() != text:
            with blocked(self.phone_edit):
                self.phone_edit.setText(text)

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
        configure_scalar_bar(self._bar, c)
        self._bar.SetVisibility(c.cmap is not None and self.points_box.isChecked())
        legend = tuple((n, tuple(col)) for n, col in c.legend)
        if legend != self._legend_mode:
            if self.legend is not None:
                scene_legend.remove_legend(self.plotter, self.legend)
                self.legend = None
            if legend:
                self.legend = scene_legend.add_legend(self.plotter, legend,
                                                      size=(0.22, min(0.6, 0.035 * len(legend) + 0.02)))
            self._legend_mode = legend or None
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
            h["local"].update(y, *t.drawn_local_frame(i))
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
            u = s.utterance_of(s.frame)
            ph = s.phone_of(s.frame) or "—"
            cls = int(m.tangent_.classes_[s.frame])
            parts.append(f"frame {s.frame} ({u.id}, t={(s.frame - u.start) / m.corpus_.rate:.2f} s, phone {ph}, "
                         f"{CLASS_LABELS[cls] if cls >= 0 else 'no step'})")
        if s.state is not None:
            parts.append(f"state {s.state}")
        if self.coloring is not None and self.coloring.readout and (s.state is not None or s.color_mode != "distance"):
            parts.append(self.coloring.readout)
        if s.target is not None:
            parts.append(f"target {s.target}: " + (f"{len(s.path) - 1} hops" if s.path is not None
                                                  else "unreachable"))
        set_readout(self.info, "; ".join(parts) if parts else "Click a point to select its state "
                    "(Shift-click or tick Path for a path to a second state)")

    def _update_hover(self):
        s = self.state
        set_readout(self.hover_label, "" if s.hover is None or s.manifold is None else
                    "under the pointer: " + hover_text(s.manifold, s, s.hover))

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
            # counted from Play too, not only from the last render: rendered just as the clock
            # starts, the markers held back the first lip frames (the first tick came ~90 ms late)
            wait += max(0.0, self._play_started - self.renderer.last_flush)
        self.renderer.request(min_interval_s=wait)

    def _on_phones(self, render=True):
        if "points" not in self.handles:
            return
        want = self.state.visible_phones
        colours = ellipsoid_colors(want)
        Y = self.state.manifold.Fy_
        for ph in sorted(want - set(self.ellipsoids)):
            verts, faces = self.state.clusters.ellipsoid(ph)
            self.ellipsoids[ph] = scene.add_cluster_ellipsoids(self.plotter, np.asarray(verts)[:, :3], faces,
                                                               colours[ph], name=f"ellipsoid_{ph}")
            members = Y[self.state.clusters.members(ph), :3]
            small = len(members) <= self.SPHERE_POINTS_MAX
            self.members[ph] = scene.add_point_markers(self.plotter, members, colours[ph],
                                                       point_size=7 if small else 4, spheres=small,
                                                       name=f"members_{ph}")
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
        self._hover_timer.stop()
        if self._hover_observer is not None:
            self.plotter.iren.remove_observer(self._hover_observer)
            self._hover_observer = None
        if self.picker is not None:
            self.picker.remove()
        self.renderer.stop()
        close_plotter(self.plotter)
