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

from PySide6 import QtCore, QtGui, QtWidgets

from app.models.picking import handle_pick
from app.scene.projection import view_transform
from app.views._common import (
    RenderScheduler,
    blocked,
    camera_of,
    close_plotter,
    connect_all,
    disconnect_all,
    make_plotter,
    set_camera,
)
from app.views.manifold.camera import ManifoldCamera
from app.views.manifold.controls import ManifoldControls
from app.views.manifold.field_controls import FieldControls
from app.views.manifold.gesture_marks import GestureMarks
from app.views.manifold.layers import ManifoldLayers, axes_origin
from app.views.manifold.legends import ManifoldLegends

__all__ = ["ManifoldView", "axes_origin"]


class ManifoldView(ManifoldControls, FieldControls, ManifoldLayers, GestureMarks, ManifoldLegends, ManifoldCamera,
                   QtWidgets.QWidget):
    """3-D view of the manifold bound to an :class:`app.models.state.AppState`.

    Its controls and readouts are :class:`app.views.manifold.controls.ManifoldControls`, its
    scene :class:`app.views.manifold.layers.ManifoldLayers`, its legends
    :class:`app.views.manifold.legends.ManifoldLegends`, its camera
    :class:`app.views.manifold.camera.ManifoldCamera`.
    """

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
        self._forget_legends()

        bar = self._make_controls()
        self.plotter = make_plotter(self)
        self.renderer = RenderScheduler(self.plotter)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(0)
        lay.addLayout(bar)
        lay.addWidget(self.plotter.interactor, 1)
        readouts = QtWidgets.QHBoxLayout()
        readouts.setContentsMargins(4, 1, 4, 1)
        readouts.addWidget(self.info, 3)
        readouts.addWidget(self.hover_label, 2)
        lay.addLayout(readouts)

        self._connect_controls(state)
        # Esc clears the selection and nothing else (the view's settings have their own reset, and undo)
        self.esc_shortcut = QtGui.QShortcut(QtGui.QKeySequence(QtCore.Qt.Key.Key_Escape), self)
        self.esc_shortcut.activated.connect(state.clear_selection)
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
            (ev.hidden_layers, lambda _h: self._sync_layer_boxes()),
        ]
        self.n_recolors = 0
        self.query_prep = None  # the worker building the state graph's query forms (see _prepare_queries)
        connect_all(self._connections)
        self._sync_horizon()
        if state.manifold is not None:
            self.rebuild()

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

    def _prepare_queries(self) -> None:
        """Build the state graph's forms for hemisphere and path queries in a worker once the new manifold's
        first frame is drawn (:meth:`engine.graph.states.StateGraph.prepare_queries`), so that neither the load
        nor the first click waits for them; a failure only leaves them to the first query."""
        from app.workers import run_task

        if self.state.manifold is None:
            return
        graph = self.state.manifold.states_
        self.query_prep = run_task(lambda _progress: graph.prepare_queries(), parent=self,
                                   title="Preparing the state graph", dialog=False, after_events=True,
                                   on_error=lambda _msg, _tb: None)

    # --------------------------------------------------------------- events
    def _on_pick(self, frame, _xyz, shift):
        handle_pick(self.state, frame, as_target=True if shift else None)

    def _sync_box(self, box, on):
        with blocked(box):
            box.setChecked(bool(on))

    def _on_changed(self, names) -> None:
        """Bring the view up to date with one action's changed fields (``events.changed``)."""
        if "manifold" in names:
            self._sync_horizon()
            self._sync_phone_edit()
            self._fill_colour_box()  # the corpus's fields
            self._sync_filter_btn()
            self.rebuild()
            self._prepare_queries()
            return
        if "palette" in names:  # a session's palette: every category colour may change
            names = names | {"color_mode", "visible_phones"}
        if names & {"hover"}:
            self._update_hover()
        if "points" not in self.handles:
            return
        s = self.state
        selection = bool(names & {"frame", "state", "target"})
        recolor = (bool(names & {"color_mode", "hemisphere", "visible_phones", "field_filter"})
                   or (s.color_mode == "distance" and bool(names & {"state", "horizon_ms"}))
                   or (s.color_mode == "phone" and "phone_filter" in names)
                   or (s.color_mode == "utterance" and "utterance" in names)
                   or (s.color_mode == "field" and "color_field" in names)
                   or (s.color_mode == "difference" and "comparison" in names))
        if names & {"color_mode", "hemisphere", "color_field"}:
            self._sync_mode_boxes()
        if "field_filter" in names:
            self._sync_filter_btn()
        if names & {"gestures", "utterance"}:
            self._on_gesture_marks(render=False)
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
        if names & {"visible_phones", "ellipsoid_opacity"}:
            self._on_phones(render=False)
        if "hidden_layers" in names:
            self._on_layers(render=False)
        if recolor:
            self._recolor(render=False)
        elif selection or "path" in names:
            self._update_info()
        if names & {"playback", "playing"} and "trajectory" not in names:
            self._on_playback(render=False)
            shown = any(r[0] == "playback position" for r in self.legend_rows.get("glyphs", ()))
            if shown != (self.state.playback is not None):  # the playback row comes and goes, once
                self._update_legends()
        if recolor or selection or names & {"path", "trajectory", "visible_phones", "horizon_ms", "phone_filter",
                                            "ellipsoid_opacity", "hidden_layers", "gestures", "utterance"}:
            self.renderer.request()
        elif names & {"playback", "playing"}:
            if "playing" in names and self.state.playing:
                self._play_started = time.perf_counter()
            self._request_playback_render()

    def resizeEvent(self, event):
        super().resizeEvent(event)
        self._update_legends()  # their boxes keep a size in pixels, so their text keeps one size

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
