"""The Compare panel: how two or more levels of a per-utterance field differ on the manifold, as a sortable table.

The user chooses a field (speaker, sex, emotion, text, group ...), its levels (a reference,
then the levels compared with it; empty: every level against the first), an optional pairing
field (the same text said in each level) and the number of permutations; **Run** checks the
request at once (a field absent, one level, levels that never share a pairing block: said in the
panel, nothing run) and fits :class:`engine.comparison.compare.ConditionComparison` in a worker
thread, its stages shown beside **Cancel** (:func:`app.models.compare_run.run_comparison`). The
result goes to the state (:attr:`app.models.state.AppState.comparison`), which the difference
view colours by; the table shows its rows, the columns of ``lipspace compare --csv``, sortable
by any column (numbers by value, missing last), filtered by family. Choosing a row makes the
views show what it describes (:func:`app.models.compare_run.apply_row`). The panel follows the
state: a comparison set elsewhere (a session) is shown here too.
"""
from __future__ import annotations

from PySide6 import QtCore, QtWidgets

from app.models.compare_run import (
    DEFAULT_PERMUTATIONS,
    ComparisonRequest,
    apply_row,
    cell_text,
    check_request,
    columns,
    run_comparison,
    sort_key,
)
from app.views._common import connect_all, disconnect_all, elided_label
from app.views.flow_layout import FlowLayout

__all__ = ["ComparePanel", "ComparisonTableModel", "FAMILY_CHOICES", "SUGGEST_MAX"]

#: a field with at most this many levels has them all put in the levels box when chosen
SUGGEST_MAX = 6
#: the family filter's entries (None: every family)
FAMILY_CHOICES = (("All comparisons", None), ("Clusters", "cluster"), ("Dynamics", "dynamics"),
                  ("States (enrichment)", "state"))


class ComparisonTableModel(QtCore.QAbstractTableModel):
    """The comparison's rows (dicts with keys :func:`app.models.compare_run.columns`), sorted on request.

    ``rows`` is the order shown; :meth:`row` gives the dict behind a shown row.
    """

    def __init__(self, parent=None):
        super().__init__(parent)
        self.cols = columns()
        self.rows: list = []

    def set_rows(self, rows) -> None:
        self.beginResetModel()
        self.rows = list(rows)
        self.endResetModel()

    def row(self, k: int) -> dict:
        return self.rows[k]

    def rowCount(self, parent=None):
        return 0 if parent is not None and parent.isValid() else len(self.rows)

    def columnCount(self, parent=None):
        return 0 if parent is not None and parent.isValid() else len(self.cols)

    def data(self, index, role=QtCore.Qt.ItemDataRole.DisplayRole):
        if not index.isValid():
            return None
        col = self.cols[index.column()]
        value = self.rows[index.row()].get(col)
        if role == QtCore.Qt.ItemDataRole.DisplayRole:
            return cell_text(col, value)
        if role == QtCore.Qt.ItemDataRole.TextAlignmentRole and not isinstance(value, str):
            return int(QtCore.Qt.AlignmentFlag.AlignRight | QtCore.Qt.AlignmentFlag.AlignVCenter)
        return None

    def headerData(self, section, orientation, role=QtCore.Qt.ItemDataRole.DisplayRole):
        if role == QtCore.Qt.ItemDataRole.DisplayRole and orientation == QtCore.Qt.Orientation.Horizontal:
            return self.cols[section]
        return None

    def sort(self, column, order=QtCore.Qt.SortOrder.AscendingOrder):
        col = self.cols[column]
        self.layoutAboutToBeChanged.emit()
        self.rows.sort(key=lambda r: sort_key(r.get(col)), reverse=order == QtCore.Qt.SortOrder.DescendingOrder)
        self.layoutChanged.emit()


class ComparePanel(QtWidgets.QWidget):
    """The comparison's request, run and table (module docstring), bound to an :class:`AppState`."""

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.state = state
        self.runner = None
        self.field_box = QtWidgets.QComboBox()
        self.field_box.setToolTip("The per-utterance field whose levels are compared")
        self.field_box.currentIndexChanged.connect(lambda _i: self._suggest_levels())
        self.levels_edit = QtWidgets.QLineEdit()
        self.levels_edit.setPlaceholderText("levels: reference, others (empty: all against the first)")
        self.levels_edit.setToolTip("A reference level, then the levels compared with it, separated by commas")
        self.pair_box = QtWidgets.QComboBox()
        self.pair_box.setToolTip("Pair by: permute the levels within each block of this field (e.g. text: the same "
                                 "sentence said in each level); none: within speaker where it can, else across")
        self.perm_spin = QtWidgets.QSpinBox()
        self.perm_spin.setRange(99, 99999)
        self.perm_spin.setSingleStep(1000)
        self.perm_spin.setValue(DEFAULT_PERMUTATIONS)
        self.perm_spin.setToolTip("Permutations of whole utterances per test")
        self.run_btn = QtWidgets.QPushButton("Run")
        self.run_btn.clicked.connect(self.run)
        self.cancel_btn = QtWidgets.QPushButton("Cancel")
        self.cancel_btn.setEnabled(False)
        self.cancel_btn.clicked.connect(self.cancel)
        self.contrast_box = QtWidgets.QComboBox()
        self.contrast_box.setToolTip("The contrast the difference colouring shows")
        self.contrast_box.currentIndexChanged.connect(self._on_contrast_chosen)
        self.family_box = QtWidgets.QComboBox()
        for text, fam in FAMILY_CHOICES:
            self.family_box.addItem(text, fam)
        self.family_box.currentIndexChanged.connect(lambda _i: self._fill_table())
        self.status = elided_label("Choose a field and press Run")
        self.model = ComparisonTableModel(self)
        self.table = QtWidgets.QTableView()
        self.table.setModel(self.model)
        self.table.setSortingEnabled(True)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QtWidgets.QAbstractItemView.SelectionMode.SingleSelection)
        self.table.verticalHeader().setVisible(False)
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.verticalHeader().setDefaultSectionSize(self.fontMetrics().height() + 6)
        self.table.selectionModel().currentRowChanged.connect(lambda cur, _prev: self.choose_row(cur.row()))
        # the controls wrap in a narrow dock, so the table keeps the height
        bar = FlowLayout(spacing=8, row_spacing=3)
        for group in ((QtWidgets.QLabel("Field:"), self.field_box), (QtWidgets.QLabel("Levels:"), self.levels_edit),
                      (QtWidgets.QLabel("Pair by:"), self.pair_box),
                      (QtWidgets.QLabel("Permutations:"), self.perm_spin), (self.run_btn, self.cancel_btn),
                      (QtWidgets.QLabel("Show:"), self.contrast_box), (self.family_box,)):
            bar.add_group(group)
        self.levels_edit.setMinimumWidth(140)
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addLayout(bar)
        lay.addWidget(self.status)
        lay.addWidget(self.table, 1)
        self._connections = [(state.events.changed, self._on_changed)]
        connect_all(self._connections)
        self._fill_fields()
        self._show_comparison()

    # ------------------------------------------------------------------ the request
    def _fill_fields(self) -> None:
        from app.models.field_colouring import utterance_field_values

        names = list(utterance_field_values(self.state)) if self.state.manifold is not None else []
        for box, first in ((self.field_box, None), (self.pair_box, "none")):
            current = box.currentData()
            box.blockSignals(True)
            box.clear()
            if first is not None:
                box.addItem(first, "")
            for n in names:
                box.addItem(n, n)
            k = box.findData(current)
            box.setCurrentIndex(k if k >= 0 else 0)
            box.blockSignals(False)
        self._suggest_levels()
        self.run_btn.setEnabled(bool(names))

    def _suggest_levels(self) -> None:
        """A field chosen: its levels in the levels box, the most frequent first (the reference), when there are
        a few (:data:`SUGGEST_MAX`); else empty, for the user to choose."""
        from app.models.field_colouring import field_levels

        name = self.field_box.currentData()
        levels = field_levels(self.state, name) if name and self.state.manifold is not None else []
        self.levels_edit.setText(", ".join(levels) if 2 <= len(levels) <= SUGGEST_MAX else "")

    def request(self) -> ComparisonRequest:
        """What the controls ask for now."""
        levels = tuple(x.strip() for x in self.levels_edit.text().split(",") if x.strip())
        horizon = self.state.horizon_ms if self.state.horizon_ms else 100.0
        return ComparisonRequest(field=str(self.field_box.currentData() or ""), levels=levels,
                                 paired_by=str(self.pair_box.currentData() or ""),
                                 n_permutations=int(self.perm_spin.value()), horizon_ms=float(horizon))

    # ------------------------------------------------------------------ running
    def run(self) -> bool:
        """Check the request, then fit it in a worker; False (the reason in the status line) when refused."""
        from app.user_messages import plain_errors
        from app.workers import run_task

        m = self.state.manifold
        if m is None or self.running:
            return False
        req = self.request()
        try:
            check_request(m, req)
        except ValueError as exc:
            self.say(str(exc), error=True)
            return False
        self.say(f"comparing {req.field}…")
        self.run_btn.setEnabled(False)
        self.cancel_btn.setEnabled(True)
        task = plain_errors(lambda progress: run_comparison(m, req, progress), doing=f"compare by {req.field}")
        self.runner = run_task(task, parent=self, title="Comparing", dialog=False, on_done=self._on_done,
                               on_error=lambda msg, _tb: self._on_end(msg, error=True),
                               on_cancel=lambda: self._on_end("cancelled; the table shows the last comparison"))
        self.runner.worker.progress.connect(self._on_progress)
        return True

    @property
    def running(self) -> bool:
        return self.runner is not None and self.runner.state == "running"

    def cancel(self) -> None:
        if self.running:
            self.runner.cancel()
            self.say("cancelling…")

    def _on_progress(self, *_args) -> None:
        if self.running:
            self.say(f"comparing: {self.runner.estimate.text()}")

    def _on_done(self, shown) -> None:
        if shown.result is not None and self.state.manifold is not None:
            self.state.set_comparison(shown)
        self._on_end("")

    def _on_end(self, message: str, error: bool = False) -> None:
        self.run_btn.setEnabled(self.state.manifold is not None)
        self.cancel_btn.setEnabled(False)
        if message:
            self.say(message, error=error)

    def say(self, message: str, error: bool = False) -> None:
        self.status.setStyleSheet("color: #a00" if error else "")
        self.status.setText(message)

    # ------------------------------------------------------------------ the result
    def _on_changed(self, names) -> None:
        if "manifold" in names:
            self.cancel()
            self._fill_fields()
        if "comparison" in names or "manifold" in names:
            self._show_comparison()

    def _show_comparison(self) -> None:
        shown = self.state.comparison
        self.contrast_box.blockSignals(True)
        self.contrast_box.clear()
        if shown is not None:
            for a, b in shown.result.contrasts_:
                self.contrast_box.addItem(f"{b} against {a}")
            self.contrast_box.setCurrentIndex(shown.contrast)
        self.contrast_box.blockSignals(False)
        self._fill_table()
        if shown is not None:
            self._show_request(shown.request)
        if shown is not None and not self.running:
            r = shown.result
            design = "; ".join(sorted({str(row["design"]) for row in r.rows_}))
            notes = " ".join(shown.notes)
            self.say(f"{shown.field}: {len(r.rows_)} comparisons, q < {r.alpha:g} in "
                     f"{sum(1 for row in r.rows_ if row['q'] < r.alpha)}; design: {design}. {notes}".strip())

    def _show_request(self, req) -> None:
        """The controls as ``req`` (the comparison shown) asked."""
        self.apply_settings({"field": req.field, "levels": list(req.levels), "paired_by": req.paired_by,
                             "n_permutations": req.n_permutations})

    def _fill_table(self) -> None:
        shown = self.state.comparison
        fam = self.family_box.currentData()
        rows = [] if shown is None else [r for r in shown.result.rows_ if fam is None or r["family"] == fam]
        self.model.set_rows(rows)
        header = self.table.horizontalHeader()
        if header.sortIndicatorSection() >= 0 and rows:
            self.model.sort(header.sortIndicatorSection(), header.sortIndicatorOrder())
        # one field per comparison (the status line names it): its column would repeat it on every row
        self.table.setColumnHidden(self.model.cols.index("field"), True)
        if rows:
            self.table.resizeColumnsToContents()

    def _on_contrast_chosen(self, i: int) -> None:
        shown = self.state.comparison
        if shown is not None and 0 <= i < len(shown.result.contrasts_) and i != shown.contrast:
            self.state.set_comparison(shown.with_contrast(i))

    def choose_row(self, k: int):
        """Make the views show what shown row ``k`` describes (returns its selection, or None)."""
        shown = self.state.comparison
        if shown is None or not 0 <= k < len(self.model.rows):
            return None
        try:
            return apply_row(self.state, shown, self.model.row(k))
        except ValueError as exc:
            self.say(str(exc), error=True)
            return None

    # ------------------------------------------------------------------ sessions
    def settings(self) -> dict:
        req = self.request()
        return {"field": req.field, "levels": list(req.levels), "paired_by": req.paired_by,
                "n_permutations": req.n_permutations}

    def apply_settings(self, d: dict) -> None:
        for box, key in ((self.field_box, "field"), (self.pair_box, "paired_by")):
            k = box.findData(d.get(key, ""))
            if k >= 0:
                box.setCurrentIndex(k)
        self.levels_edit.setText(", ".join(d.get("levels", [])))  # after the field (which suggests its levels)
        self.perm_spin.setValue(int(d.get("n_permutations", DEFAULT_PERMUTATIONS)))

    def close_view(self) -> None:
        self.cancel()
        disconnect_all(self._connections)
