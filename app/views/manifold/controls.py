"""The manifold view's controls: colouring, hemisphere and horizon, layers, standard views, readouts (the colour
box and the field filter are :mod:`app.views.manifold.field_controls`').

A part of :class:`app.views.manifold_view.ManifoldView` (a mixin): the widgets, how they
write the state, and how they follow it.
"""
from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtWidgets

from app.models.colouring import CLASS_LABELS
from app.models.picking import hover_text
from app.models.state.fields import HEMISPHERES
from app.views._common import blocked, elided_label
from app.views.flow_layout import FlowLayout
from app.views.manifold.field_controls import COLOR_LABELS

__all__ = ["ManifoldControls", "COLOR_LABELS", "HEMI_LABELS", "HORIZON_SLIDER_MS"]

HEMI_LABELS = {"future": "Future hemisphere", "past": "Past hemisphere", "both": "Past and future",
               "off": "No hemisphere"}
#: the horizon slider runs 0..HORIZON_SLIDER_MS in whole frame periods; the "Horizon" box off means no horizon
HORIZON_SLIDER_MS = 500


class ManifoldControls:
    """The control bar and readouts of :class:`app.views.manifold_view.ManifoldView`."""

    def _make_controls(self) -> FlowLayout:
        """Make the controls; returns their bar (groups that wrap to a new row in a narrow window)."""
        self._make_field_controls()  # the colour box and the field filter
        self.hemi_box = QtWidgets.QComboBox()
        for m in HEMISPHERES:
            self.hemi_box.addItem(HEMI_LABELS[m], m)
        self.hemi_box.setToolTip("Which hemisphere of the clicked state to colour by directed hop distance")
        self.hemi_box.setSizeAdjustPolicy(QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToContents)
        self.path_box = QtWidgets.QCheckBox("Path")
        self.path_box.setToolTip("Tick (or hold Shift) and click a second point to draw the minimum-distance "
                                 "path between the two states")
        self.layer_boxes = {}
        for key, label, tip in (("points", "Points", "Show the frames (hide them to see trajectories and paths alone)"),
                                ("plane", "Plane", "Show the zero-velocity plane"),
                                ("axes", "Axes", "Show the named axes Y1-Y3 and the global shape (S) and velocity (V) "
                                 "directions"),
                                ("legend", "Legend", "Show the legends of the colours and of every glyph drawn")):
            box = QtWidgets.QCheckBox(label)
            box.setChecked(True)
            box.setToolTip(tip)
            self.layer_boxes[key] = box
        self.points_box, self.plane_box, self.axes_box = (self.layer_boxes[k] for k in ("points", "plane", "axes"))
        self.clear_btn = QtWidgets.QPushButton("Clear selection")
        self.clear_btn.setToolTip("Clear the selected frame, state, target and path (Esc); colours, horizon, filter "
                                  "and ellipsoids stay (View › Reset view settings resets them)")
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
        # the selection and the pointer's frame share one line under the view, each elided (whole in its
        # tooltip): their height never changes, so the 3-D view never jumps, and a laptop's screen keeps it tall
        self.info = elided_label("Click a point to select its state")
        self.hover_label = elided_label("")
        self.hover_label.setStyleSheet("color: #444")

        # controls in groups that wrap to a new row in a narrow window (FlowLayout): the view's minimum
        # width is that of its widest group, not of every control side by side
        bar = FlowLayout(spacing=10, row_spacing=3)
        for group in ((QtWidgets.QLabel("Colour:"), self.color_box, self.phone_edit),
                      (self.hemi_box, self.horizon_box, self.horizon_slider, self.horizon_label),
                      (self.filter_btn,),
                      (self.path_box, *self.layer_boxes.values()),
                      (*self.view_btns.values(), self.clear_btn)):
            bar.add_group(group)
        return bar

    def _connect_controls(self, state) -> None:
        self.hemi_box.currentIndexChanged.connect(lambda _: state.set_hemisphere(self.hemi_box.currentData()))
        self.path_box.toggled.connect(state.set_path_mode)
        for key, box in self.layer_boxes.items():
            box.toggled.connect(lambda on, k=key: state.set_layer_visible(k, on))
        self.clear_btn.clicked.connect(state.clear_selection)
        self.horizon_box.toggled.connect(lambda _on: self._push_horizon())
        self.horizon_slider.valueChanged.connect(lambda _v: self._push_horizon())
        self.phone_edit.editingFinished.connect(self._push_phone_filter)

    def _sync_layer_boxes(self):
        for key, box in self.layer_boxes.items():
            with blocked(box):
                box.setChecked(key not in self.state.hidden_layers)

    def _sync_mode_boxes(self):
        self._sync_colour_box()
        with blocked(self.hemi_box):
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
        self.info.setText("; ".join(parts) if parts else "Click a point to select its state "
                    "(Shift-click or tick Path for a path to a second state)")

    def _update_hover(self):
        s = self.state
        self.hover_label.setText("" if s.hover is None or s.manifold is None else
                    "under the pointer: " + hover_text(s.manifold, s, s.hover))

