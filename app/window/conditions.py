"""The window's views of a corpus's conditions: the small multiples and the Compare panel, docked and linked.

:class:`app.views.small_multiples.SmallMultiples` (one manifold view per level of the colour
field) is docked as a tab beside the lips when shown (it starts hidden: View menu,
:meth:`ConditionDocks.show_compare`), :class:`app.views.compare_panel.ComparePanel` beside the clusters.
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
        self.tabifyDockWidget(self.docks["scree"], self.docks["compare"])
        self.docks["clusters"].raise_()  # the tab first shown stays the one shown before
        # shown on demand (View menu): a tab beside the lips, made when shown (a tab bar made over a hidden
        # dock stayed on screen, naming it, and a tab bar over the lips costs them room on a laptop)
        self.docks["multiples"].hide()
        self.docks["multiples"].toggleViewAction().triggered.connect(self._tab_multiples)
        camera = self.manifold_view.plotter.renderer.GetActiveCamera()
        self.small_multiples.link_camera(camera)
        self.camera_link = CameraLink(camera, [(self.manifold_view.plotter, self.manifold_view.renderer),
                                               (self.small_multiples.plotter, self.small_multiples.renderer)])

    def _tab_multiples(self, *_checked) -> None:
        """The small multiples, shown in the right column, become a tab beside the lips."""
        lips, multiples = self.docks["lips"], self.docks["multiples"]
        right = QtCore.Qt.DockWidgetArea.RightDockWidgetArea
        if (not multiples.isHidden() and not multiples.isFloating() and not lips.isFloating() and not lips.isHidden()
                and self.dockWidgetArea(multiples) == right and self.dockWidgetArea(lips) == right
                and lips not in self.tabifiedDockWidgets(multiples)):
            self.tabifyDockWidget(lips, multiples)

    def show_compare(self) -> None:
        """Bring the Compare panel and the small multiples to the front."""
        for key in ("compare", "multiples"):
            self.docks[key].show()
            if key == "multiples":
                self._tab_multiples()
            self.docks[key].raise_()
        # the table wants rows to read: three fifths of the column's height
        h = max(self.docks["multiples"].height() + self.docks["compare"].height(), 2)
        self.resizeDocks([self.docks["multiples"], self.docks["compare"]], [2 * h // 5, 3 * h // 5],
                         QtCore.Qt.Orientation.Vertical)

    def _close_condition_views(self) -> None:
        self.camera_link.remove()
        self.compare_panel.close_view()
        self.small_multiples.close_view()
