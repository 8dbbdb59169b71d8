"""The window's views of a corpus's conditions: the small multiples and the Compare panel, docked and linked.

:class:`app.views.small_multiples.SmallMultiples` (one manifold view per level of the colour
field) is docked beside the lips, :class:`app.views.compare_panel.ComparePanel` beside the
clusters. The small multiples' dock starts hidden (View menu; :meth:`ConditionDocks.show_compare` shows it).
The small multiples show the manifold view's own camera
(:class:`app.views.camera_link.CameraLink` renders every view showing it once when it turns);
selection, horizon and colours are the state's, so they follow by design. Neither view calls
another: both observe the state.
"""
from __future__ import annotations

from PySide6 import QtCore, QtWidgets

__all__ = ["ConditionDocks"]


class ConditionDocks:
    """The small multiples' and the Compare panel's docks of :class:`app.main_window.MainWindow`."""

    def _make_condition_docks(self) -> None:
        from app.views.camera_link import CameraLink
        from app.views.compare_panel import ComparePanel
        from app.views.small_multiples import SmallMultiples

        self.small_multiples = SmallMultiples(self.state)
        self.compare_panel = ComparePanel(self.state)
        right = QtCore.Qt.DockWidgetArea.RightDockWidgetArea
        for key, title, widget in (("multiples", "Small multiples", self.small_multiples),
                                   ("compare", "Compare", self.compare_panel)):
            dock = QtWidgets.QDockWidget(title, self)
            dock.setObjectName(f"dock_{key}")
            dock.setWidget(widget)
            self.addDockWidget(right, dock)
            self.docks[key] = dock
        self.tabifyDockWidget(self.docks["lips"], self.docks["multiples"])
        self.tabifyDockWidget(self.docks["scree"], self.docks["compare"])
        for key in ("lips", "clusters"):  # the tabs first shown stay those shown before
            self.docks[key].raise_()
        # shown on demand (View menu, the Compare panel): a tab bar over the lips costs them room on a laptop
        self.docks["multiples"].hide()
        camera = self.manifold_view.plotter.renderer.GetActiveCamera()
        self.small_multiples.link_camera(camera)
        self.camera_link = CameraLink(camera, [(self.manifold_view.plotter, self.manifold_view.renderer),
                                               (self.small_multiples.plotter, self.small_multiples.renderer)])

    def show_compare(self) -> None:
        """Bring the Compare panel and the small multiples to the front."""
        for key in ("compare", "multiples"):
            self.docks[key].show()
            self.docks[key].raise_()
        # the table wants rows to read: three fifths of the column's height
        h = max(self.docks["multiples"].height() + self.docks["compare"].height(), 2)
        self.resizeDocks([self.docks["multiples"], self.docks["compare"]], [2 * h // 5, 3 * h // 5],
                         QtCore.Qt.Orientation.Vertical)

    def _close_condition_views(self) -> None:
        self.camera_link.remove()
        self.compare_panel.close_view()
        self.small_multiples.close_view()
