"""Progress of a background task in the status bar: stage, count, elapsed time, time left, Cancel.

Loading a corpus or the synthetic talker runs in a worker thread
(:mod:`app.workers`); this widget shows its progress without a modal dialog, so the
window stays usable (menus, File › Open, the views) while it runs. Stages that
report no total (``total <= 0``), and stages whose count has reached its total while
the work goes on, show a busy bar rather than a bar frozen at 100 %; the label
shows the seconds spent in the current stage, refreshed twice a second so a long stage
visibly lives, and the time left (:class:`app.models.task_status.ProgressEstimate`: the
stage's own pace, and over the known stages of opening a talker or a recording).
"""
from __future__ import annotations

import time

from PySide6 import QtCore, QtWidgets

from app.models.task_status import ProgressEstimate

__all__ = ["TaskProgress", "attach_status_progress"]


class TaskProgress(QtWidgets.QWidget):
    """Status-bar progress for one :class:`app.workers.TaskRunner` at a time.

    Attributes
    ----------
    runner : TaskRunner or None
        The task shown (None when idle; the widget is hidden then).
    stages : list of (str, float)
        Each stage seen and the ``time.perf_counter()`` it started, for tools and tests.
    """

    def __init__(self, parent=None):
        super().__init__(parent)
        self.runner = None
        self.stages: list[tuple[str, float]] = []
        self._last = ("", 0, 0)
        self.label = QtWidgets.QLabel("")
        self.bar = QtWidgets.QProgressBar()
        self.bar.setMaximumWidth(180)
        self.bar.setTextVisible(False)
        self.cancel_btn = QtWidgets.QToolButton()
        self.cancel_btn.setText("Cancel")
        self.cancel_btn.setToolTip("Stop loading (the window keeps what it shows)")
        self.cancel_btn.clicked.connect(self.cancel)
        lay = QtWidgets.QHBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        for w in (self.label, self.bar, self.cancel_btn):
            lay.addWidget(w)
        self._clock = QtCore.QTimer(self)
        self._clock.setInterval(500)
        self._clock.timeout.connect(self._refresh)
        self.hide()

    def attach(self, runner, title: str = "") -> None:
        """Show ``runner``'s progress until it finishes, fails or is cancelled."""
        if self.runner is not None:
            self._disconnect()
        self.runner = runner
        self.stages = [(title or "starting", time.perf_counter())]
        self._last = (title or "starting", 0, 0)
        self.estimate = ProgressEstimate()
        self.estimate.report(title or "starting", 0, 0)
        runner.progressed.connect(self._on_progress)
        for sig in (runner.finished, runner.failed, runner.cancelled):
            sig.connect(self._on_end)
        self.cancel_btn.setEnabled(True)
        self._refresh()
        self.show()
        self._clock.start()

    def cancel(self) -> None:
        if self.runner is not None:
            self.runner.cancel()
            self.cancel_btn.setEnabled(False)
            self.label.setText("cancelling…")

    def _on_progress(self, stage, done, total) -> None:
        if self.runner is None or self.runner.worker.cancel_requested:
            return
        if stage != self.stages[-1][0]:
            self.stages.append((stage, time.perf_counter()))
        self._last = (stage, int(done), int(total))
        self.estimate.report(stage, done, total)
        self._refresh()

    def _refresh(self) -> None:
        if self.runner is None or self.runner.worker.cancel_requested:
            return
        stage, done, total = self._last
        if total > 0 and done < total:
            self.bar.setRange(0, total)
            self.bar.setValue(done)
        else:  # no total, or the count is complete while the stage still works: busy, not 100 %
            self.bar.setRange(0, 0)
        self.label.setText(self.estimate.text())

    def _on_end(self, *_args) -> None:
        self._disconnect()
        self.runner = None
        self._clock.stop()
        self.hide()

    def _disconnect(self) -> None:
        r = self.runner
        for sig, slot in ((r.progressed, self._on_progress), (r.finished, self._on_end),
                          (r.failed, self._on_end), (r.cancelled, self._on_end)):
            try:
                sig.disconnect(slot)
            except (RuntimeError, TypeError):
                pass


def attach_status_progress(window, runner, title: str = "") -> TaskProgress:
    """Show ``runner`` in ``window``'s status bar (one :class:`TaskProgress` per window, made on first use)."""
    w = window.findChild(TaskProgress, "task_progress")
    if w is None:
        w = TaskProgress(window)
        w.setObjectName("task_progress")
        window.statusBar().addPermanentWidget(w)
    w.attach(runner, title)
    return w
