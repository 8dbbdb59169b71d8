"""Clusters panel: the phone table (counts, opening-side fraction, separation) with ellipsoid toggles.

Numbers come from :class:`engine.manifold.clusters.PhoneClusters` (built once per manifold
and cached on the state); ticking a phone shows its 2-s.d. ellipsoid in the
manifold view. Each row's swatch is its label's colour in the session palette
(``state.palette``): the colour of its ellipsoid, of its points in phone colouring, of its
legend row and of its box in the timeline. "Fill" sets how opaque the ellipsoids' fill is
(their outline stays). A corpus without phone labels shows the clusters of its four
kinematic landmarks (aperture maxima, minima, peak opening and closing velocities), named
as landmarks: the first column is "Landmark".
"""
from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from app.views._common import blocked, connect_all, disconnect_all, elided_label

__all__ = ["ClustersPanel", "COLUMNS"]

#: (key in the row dict, header, tooltip)
COLUMNS = (
    ("phone", "Phone", "phone label (the corpus's own set)"),
    ("count", "Count", "phone instances (mid-point frames), as the paper's Table 1"),
    ("opening_fraction", "Opening", "fraction of mid-points on the opening side of the zero-velocity plane"),
    ("lipreading_class", "Lip class", "protected / invisible / normal (the unit-selection paper's classes)"),
    ("nearest_y", "Nearest (Y)", "the closest other phone with dynamics (in Y)"),
    ("separation_y", "Sep. Y", "Bhattacharyya distance to the nearest phone in Y (shape + velocity)"),
    ("separation_x", "Sep. X", "Bhattacharyya distance to the same phone in X (shape only)"),
)


#: item data role holding the colour of the swatch an item shows
_SWATCH_ROLE = QtCore.Qt.ItemDataRole.UserRole + 1


def _swatch(rgb) -> QtGui.QIcon:
    pm = QtGui.QPixmap(12, 12)
    pm.fill(QtGui.QColor.fromRgbF(*[float(c) for c in rgb]))
    return QtGui.QIcon(pm)


class ClustersPanel(QtWidgets.QWidget):
    """Phone table bound to an :class:`app.models.state.AppState`."""

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.state = state
        self.rows: list[dict] = []
        self.kind = "phones"  # or "kinematic": what the rows are clusters of
        self._palette: dict = {}
        self.table = QtWidgets.QTableWidget(0, len(COLUMNS))
        self.table.setHorizontalHeaderLabels([h for _k, h, _t in COLUMNS])
        for j, (_k, _h, tip) in enumerate(COLUMNS):
            self.table.horizontalHeaderItem(j).setToolTip(tip)
        self.table.verticalHeader().setVisible(False)
        # rows as tall as their text needs: a laptop's screen shows five of them and more
        self.table.verticalHeader().setDefaultSectionSize(self.table.fontMetrics().height() + 6)
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSortingEnabled(True)
        self.table.horizontalHeader().setSectionResizeMode(QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        # one line, elided, never wrapped under the dock's tab bar: the whole explanation is its tooltip
        self.note = elided_label("")
        self.none_btn = QtWidgets.QPushButton("Hide all")
        self.none_btn.setToolTip("Hide every ellipsoid")
        self.opacity_slider = QtWidgets.QSlider(QtCore.Qt.Orientation.Horizontal)
        self.opacity_slider.setRange(0, 100)
        self.opacity_slider.setMaximumWidth(110)
        self.opacity_slider.setToolTip("How opaque the ellipsoids' fill is (0: outline only); undo with Ctrl+Z")
        row = QtWidgets.QHBoxLayout()
        row.setContentsMargins(0, 0, 0, 0)
        row.addWidget(self.note, 1)
        row.addWidget(QtWidgets.QLabel("Fill"))
        row.addWidget(self.opacity_slider)
        row.addWidget(self.none_btn)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(2, 2, 2, 2)
        lay.addWidget(self.table, 1)
        lay.addLayout(row)
        self.table.itemChanged.connect(self._on_item)
        self.none_btn.clicked.connect(lambda: state.set_visible_phones(()))
        self.opacity_slider.valueChanged.connect(lambda v: state.set_ellipsoid_opacity(v / 100.0))
        ev = state.events
        self._connections = [(ev.manifold, lambda _m: self.rebuild()), (ev.visible_phones, self._sync_checks),
                             (ev.palette, lambda _p: self._recolour()), (ev.ellipsoid_opacity, self._sync_opacity)]
        connect_all(self._connections)
        self._sync_opacity(state.ellipsoid_opacity)
        self.rebuild()

    def table_rows(self) -> list[dict]:
        """The table as rows of dicts (what File > Export cluster table writes); landmark clusters name their
        first column ``landmark``."""
        if self.kind != "kinematic":
            return [dict(r) for r in self.rows]
        return [{("landmark" if k == "phone" else k): v for k, v in r.items()} for r in self.rows]

    #: (header of the first column, singular noun) per kind of clusters
    NAMES = {"phones": ("Phone", "phone"), "kinematic": ("Landmark", "landmark")}

    def rebuild(self) -> None:
        m = self.state.manifold
        self.rows = []
        self.kind = "phones"
        if m is not None:
            try:
                self.rows = self.state.cluster_rows()
                self.kind = self.state.cluster_kind
                noun = self.NAMES[self.kind][1]
                what = ("No phone labels: kinematic landmarks of the lip aperture (open = maxima, "
                        "closed = minima, opening / closing = peak velocities). " if self.kind == "kinematic" else "")
                self.note.setText(f"{what}Tick a {noun} to show its 2-s.d. ellipsoid in the manifold view, in "
                                  f"the {noun}'s colour (the swatch); View › Frame selection (F) brings the ticked "
                                  "ellipsoids into view. Separations are Bhattacharyya distances (0 = identical "
                                  "clusters) in Y (with dynamics) and X (shape only), from the "
                                  f"{noun}'s nearest neighbour in Y.")
            except (ImportError, ValueError) as exc:
                self.note.setText(f"phone clusters unavailable: {exc}")
        header = self.NAMES[self.kind][0]
        item = self.table.horizontalHeaderItem(0)
        item.setText(header)
        item.setToolTip(COLUMNS[0][2] if self.kind == "phones" else
                        "kinematic landmark of the lip aperture: open, closed, opening, closing")
        self._palette = palette = self._row_colours()
        with blocked(self.table):
            self.table.setSortingEnabled(False)
            self.table.setRowCount(len(self.rows))
            for i, r in enumerate(self.rows):
                for j, (key, _h, _t) in enumerate(COLUMNS):
                    v = r.get(key)
                    item = QtWidgets.QTableWidgetItem()
                    if isinstance(v, (float, np.floating)):
                        item.setData(QtCore.Qt.ItemDataRole.DisplayRole, round(float(v), 3))
                    elif isinstance(v, (int, np.integer)):
                        item.setData(QtCore.Qt.ItemDataRole.DisplayRole, int(v))
                    else:
                        item.setText("" if v is None else str(v))
                    if key == "phone":
                        item.setFlags(item.flags() | QtCore.Qt.ItemFlag.ItemIsUserCheckable)
                        item.setCheckState(QtCore.Qt.CheckState.Checked if v in self.state.visible_phones
                                           else QtCore.Qt.CheckState.Unchecked)
                        self._set_swatch(item, palette.get(v))
                    self.table.setItem(i, j, item)
            self.table.setSortingEnabled(True)
            self.table.sortItems(1, QtCore.Qt.SortOrder.DescendingOrder)  # most frequent first (Table 1)

    def _row_colours(self) -> dict:
        """``{label: (r, g, b)}`` of the rows in the session palette ({} without a manifold or palette)."""
        pal = self.state.palette
        if self.state.manifold is None or pal is None:
            return {}
        return pal.colours("landmark" if self.kind == "kinematic" else "phone", [r["phone"] for r in self.rows])

    def _recolour(self) -> None:
        """The palette changed (not the rows): each swatch takes its label's new colour."""
        self._palette = self._row_colours()
        with blocked(self.table):
            for i in range(self.table.rowCount()):
                it = self.table.item(i, 0)
                if it is not None:
                    self._set_swatch(it, self._palette.get(it.text()))

    def _on_item(self, item):
        if item.column() != 0:
            return
        self.state.set_phone_visible(item.text(), item.checkState() == QtCore.Qt.CheckState.Checked)

    def _sync_checks(self, visible):
        """Tick the visible phones (each swatch keeps its label's one colour, ticked or not)."""
        with blocked(self.table):
            for i in range(self.table.rowCount()):
                it = self.table.item(i, 0)
                if it is not None:
                    check = QtCore.Qt.CheckState.Checked if it.text() in visible else QtCore.Qt.CheckState.Unchecked
                    if it.checkState() != check:
                        it.setCheckState(check)

    def _sync_opacity(self, opacity):
        with blocked(self.opacity_slider):
            self.opacity_slider.setValue(int(round(100 * float(opacity))))

    def swatch(self, label):
        """The colour (r, g, b) the row of ``label`` shows (None: no such row)."""
        return self._palette.get(label)

    @staticmethod
    def _set_swatch(item, rgb) -> None:
        """Show ``rgb``'s swatch on ``item`` unless it already shows it: each new icon makes the table
        re-measure its columns (~3 ms a row), so a toggle re-draws only the rows whose colour changed."""
        if rgb is None:
            return
        key = QtGui.QColor.fromRgbF(*[float(c) for c in rgb]).name()
        if item.data(_SWATCH_ROLE) != key:
            item.setData(_SWATCH_ROLE, key)
            item.setIcon(_swatch(rgb))

    def close_view(self) -> None:
        disconnect_all(self._connections)
