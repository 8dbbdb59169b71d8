"""Scree panel: explained variance of X and Y, and each X component as a lip deformation.

Its plot (matplotlib's Qt canvas) is made when the panel first comes on screen
(:meth:`ScreePanel.set_on_screen`; the window calls it when the panel's dock tab is raised): the
panel starts as a tab behind the clusters table, and making the plot cost the window 0.3-0.5 s.
"""
from __future__ import annotations

import numpy as np
from PySide6 import QtWidgets

from app.models.scree import scree_series
from app.views._common import blocked, connect_all, disconnect_all, elided_label

__all__ = ["ScreePanel"]

MAX_SHOWN = 30


class ScreePanel(QtWidgets.QWidget):
    """Scree of X (blue) and Y (red), paper fig. 1(b) style, with a component chooser."""

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.state = state
        self.figure = self.canvas = None  # made when the panel is first on screen (set_on_screen)
        self.show_box = QtWidgets.QCheckBox("Show X component")
        self.show_box.setToolTip("Show the component as the mean lip shape −2 s.d. and +2 s.d. in the lip view")
        self.spin = QtWidgets.QSpinBox()
        self.spin.setMinimum(1)
        self.readout = elided_label("")  # one line, never squeezing the box and the spin beside it
        row = QtWidgets.QHBoxLayout()
        row.addWidget(self.show_box)
        row.addWidget(self.spin)
        row.addWidget(self.readout, 1)
        self._layout = lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(2, 2, 2, 2)
        lay.addStretch(1)  # the plot's place until it is made
        lay.addLayout(row)
        self.show_box.toggled.connect(lambda _on: self._push())
        self.spin.valueChanged.connect(lambda _v: self._push())
        ev = state.events
        self._connections = [(ev.manifold, lambda _m: self.rebuild()), (ev.component, self._on_component)]
        connect_all(self._connections)
        self.rebuild()

    def _make_plot(self) -> None:
        """Put the plot in the panel (in the place the stretch held)."""
        from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
        from matplotlib.figure import Figure

        self.figure = Figure(figsize=(4, 3))
        self.figure.subplots_adjust(left=0.16, right=0.97, bottom=0.2, top=0.95)
        self.canvas = FigureCanvasQTAgg(self.figure)
        self.canvas.mpl_connect("resize_event", lambda _e: self._fit_layout())
        self._layout.takeAt(0)
        self._layout.insertWidget(0, self.canvas, 1)

    def set_on_screen(self, on_screen: bool) -> None:
        """The panel came on screen (its dock's tab raised, its dock shown) or left it: the plot is made
        the first time. (Qt shows a dock's widget behind another tab too, so showEvent cannot tell.)"""
        if on_screen and self.canvas is None:
            self._make_plot()
            self.rebuild()

    def rebuild(self) -> None:
        m = self.state.manifold
        if m is not None:
            n = int(m.shape_.n_components_)
            with blocked(self.spin):
                self.spin.setMaximum(n)
            self.spin.setSuffix(f" / {n}")
            self._on_component(self.state.component)
        if self.figure is None:
            return  # drawn when the panel is first on screen
        self.figure.clear()
        if m is None:
            self.canvas.draw_idle()
            return
        d = scree_series(m)
        ax = self.figure.add_subplot(111)
        nx, ny = min(MAX_SHOWN, d["x"].size), d["y"].size
        ax.plot(np.arange(1, nx + 1), 100 * (1 - d["x_cum"][:nx]), "o-", color="tab:blue", ms=3,
                label="X residual (shape)")
        ax.plot(np.arange(1, ny + 1), 100 * (1 - d["y_cum"]), "s-", color="tab:red", ms=3,
                label="Y residual (shape + velocity)")
        ax.set_xlabel("components")
        ax.set_ylabel("residual variance (%)")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, frameon=False)
        self._fit_layout()
        self.canvas.draw_idle()

    def _fit_layout(self):
        """Tight margins for the current size (skipped while the panel is hidden or tiny)."""
        if self.canvas is None:
            return
        w, h = self.canvas.get_width_height()
        if self.figure.axes and w > 150 and h > 120:
            self.figure.tight_layout(pad=0.5)

    def _push(self):
        if self.state.manifold is None:
            return
        self.state.set_component(self.spin.value() - 1 if self.show_box.isChecked() else None)

    def _on_component(self, i):
        with blocked(self.show_box, self.spin):
            self.show_box.setChecked(i is not None)
            if i is not None:
                self.spin.setValue(i + 1)
        m = self.state.manifold
        if m is None:
            self.readout.setText("")
            return
        k = self.spin.value() - 1
        ratio = float(m.shape_.scree_[k]) if k < len(m.shape_.scree_) else float("nan")
        self.readout.setText(f"X{k + 1}: {100 * ratio:.1f}% of the variance")

    def hideEvent(self, event) -> None:  # noqa: N802 (Qt)
        """Leaving the panel (another tab, dock closed) ends the component view: the lip view follows clicks."""
        if self.state.component is not None:
            self.state.set_component(None)
        super().hideEvent(event)

    def close_view(self) -> None:
        disconnect_all(self._connections)
