"""The explorer's main window: the manifold view in the centre, the other views docked around it.

Every view observes one :class:`app.models.state.AppState`; the window only wires its docks,
loading (in a worker thread, progress in the status bar) and layout here; its menus
(:mod:`app.window.menus`), sessions (:mod:`app.window.sessions`) and File › Export dialogs
(:mod:`app.window.exports`) are parts of it; :func:`app.launching.launch` starts it, and
stops it on a signal (:mod:`app.window.signals`).
"""
from __future__ import annotations

from pathlib import Path

from PySide6 import QtCore, QtGui, QtWidgets

from app.models.state import AppState
from app.window.conditions import ConditionDocks
from app.window.exports import ANIMATION_FILTERS, FIGURE_FILTERS, TRAJECTORY_FILTERS, ExportActions
from app.window.menus import MenuActions
from app.window.sessions import SessionActions

__all__ = ["MainWindow", "TRAJECTORY_FILTERS", "ANIMATION_FILTERS", "FIGURE_FILTERS"]


class MainWindow(MenuActions, SessionActions, ExportActions, ConditionDocks, QtWidgets.QMainWindow):
    """Docked views over one :class:`AppState`.

    Parameters
    ----------
    manifold : engine.manifold.model.Manifold or None
        Shown at once when given; otherwise use :meth:`open_source`.
    state : AppState, optional
    source : dict, optional
        Where ``manifold`` came from (``path``, ``preset``, the synthetic talker's ``kinematics``),
        for the title and session files.
    autosave : app.files.autosave.Autosaver, optional
        Saves the session a few seconds after it changes (:mod:`app.files.autosave`).
    settings : app.window_settings.WindowSettings, optional
        Where geometry, dock layout and recent files are remembered (default: the user's
        settings, :func:`app.window_settings.open_settings`).
    """

    def __init__(self, manifold=None, *, state: AppState | None = None, source: dict | None = None,
                 autosave=None, settings=None):
        super().__init__()
        from app.views import ClustersPanel, LipView, ManifoldView, ScreePanel, TrajectoryEditor
        from app.window_settings import WindowSettings

        self.state = state or AppState()
        self.settings = settings if settings is not None else WindowSettings()
        self._help = None
        self.setWindowTitle("Lipspace")
        self.resize(1400, 900)
        self._runner = None
        self._pending_session = None
        self.last_dir = str(Path.cwd())

        self.manifold_view = ManifoldView(self.state, self)
        self.setCentralWidget(self.manifold_view)
        self.lip_view = LipView(self.state)
        self.editor = TrajectoryEditor(self.state)
        self.clusters = ClustersPanel(self.state)
        self.scree = ScreePanel(self.state)
        self.docks = {}
        for key, title, widget, area in (
                ("lips", "Lips", self.lip_view, QtCore.Qt.DockWidgetArea.RightDockWidgetArea),
                ("clusters", "Phone clusters", self.clusters, QtCore.Qt.DockWidgetArea.RightDockWidgetArea),
                ("scree", "Scree and components", self.scree, QtCore.Qt.DockWidgetArea.RightDockWidgetArea),
                ("editor", "Trajectory editor", self.editor, QtCore.Qt.DockWidgetArea.BottomDockWidgetArea)):
            dock = QtWidgets.QDockWidget(title, self)
            dock.setObjectName(f"dock_{key}")
            dock.setWidget(widget)
            self.addDockWidget(area, dock)
            self.docks[key] = dock
        # the editor's title on its side: on a laptop's screen every pixel of height goes to the 3-D view
        ed = self.docks["editor"]
        ed.setFeatures(ed.features() | QtWidgets.QDockWidget.DockWidgetFeature.DockWidgetVerticalTitleBar)
        self.tabifyDockWidget(self.docks["clusters"], self.docks["scree"])
        self.docks["clusters"].raise_()
        self.docks["scree"].visibilityChanged.connect(self.scree.set_on_screen)  # its plot made when first seen
        self._make_condition_docks()  # the small multiples and the Compare panel
        self._size_docks()
        self._set_minimum_sizes()
        self._default_layout = self.saveState()  # View > Reset layout goes back to this

        self.summary_label = QtWidgets.QLabel("no manifold loaded")
        self.statusBar().addPermanentWidget(self.summary_label)
        from app.window.undo import SettingsRecorder

        self.view_undo_stack = QtGui.QUndoStack(self)  # the view's settings (the editor keeps its own edits)
        self.settings_recorder = SettingsRecorder(self.state, self.view_undo_stack)
        self._make_menus()
        self.state.events.manifold.connect(self._on_manifold)
        self.autosaver = autosave
        self._autosave_timer = QtCore.QTimer(self)
        self._autosave_timer.timeout.connect(self._autosave_tick)
        if autosave is not None:
            self._autosave_timer.start(1000)
        self.layout_restored = self.settings.restore_layout(self)
        # the editor's dock is as tall as what the editor shows: no room kept for a sound that is off or absent,
        # neither now nor from a layout saved while a sound was shown
        self.editor.heightWanted.connect(self._fit_editor_dock)
        self._fit_editor_dock()
        # why there is no sound, said once each in the status bar (no device or library, no espeak-ng)
        self._said: set = set()
        self.editor.notice.connect(self.say_once)
        self.state.events.playing.connect(self._check_sound)
        if manifold is not None:
            self.set_manifold(manifold, source=source)

    #: smallest useful size of each view: below it the window stops shrinking instead of
    #: collapsing a dock to nothing (the Lips dock vanished at 1179 x 407 before)
    VIEW_MINIMUM = {"manifold": (360, 260), "lips": (240, 170), "clusters": (240, 150), "scree": (240, 150),
                    "editor": (560, 120), "multiples": (240, 170), "compare": (240, 150)}

    def _set_minimum_sizes(self) -> None:
        views = {"manifold": self.manifold_view, **{k: d.widget() for k, d in self.docks.items()}}
        for key, view in views.items():
            hint = view.minimumSizeHint()  # never below what the view's own layout needs
            if key == "editor":  # its height follows its width (its controls wrap): it keeps it itself
                view.setMinimumWidth(max(self.VIEW_MINIMUM[key][0], hint.width()))
                continue
            view.setMinimumSize(max(self.VIEW_MINIMUM[key][0], hint.width()),
                                max(self.VIEW_MINIMUM[key][1], hint.height()))
        self.setMinimumSize(self.minimumSizeHint())

    # ------------------------------------------------------------------ data
    def set_manifold(self, manifold, *, source: dict | None = None) -> None:
        self.state.set_manifold(manifold, source=source)

    def _on_manifold(self, m):
        if m is None:
            self.summary_label.setText("no manifold loaded")
            return
        s = m.summary()
        self.summary_label.setText(
            f"{s['corpus']}: {s['frames']} frames, {s['utterances']} utterances, {s['points']} points · "
            f"X {s['shape_components']} comp. ({100 * s['shape_variance_kept']:.1f}%) · Y {s['embedding_dims']}-D, "
            f"first 3 hold {100 * s['Y_first3_recovered']:.0f}% · K={s['n_states']} states")
        from app.files.source_loading import talker_name

        src = self.state.source
        name = (Path(src["path"]).name if src.get("path")
                else talker_name(src.get("preset", "default"), src.get("kinematics", "classic")))
        self.setWindowTitle(f"Lipspace — {name}")

    def open_source(self, path=None, *, preset: str = "default", kinematics: str = "classic",
                    session: dict | None = None, started=None):
        """Load a manifold / corpus file (or the synthetic talker ``preset`` with ``kinematics``,
        ``"classic"`` or ``"calibrated"``) in a worker; returns the runner.

        ``started``: a :class:`app.workers.TaskRunner` already loading this source (begun by
        :func:`app.launching.launch` before the window was built), taken over instead of a new one.
        """
        from app.files.source_loading import loading_task
        from app.views.task_progress import attach_status_progress
        from app.workers import connect_outcome, run_task

        what, task = loading_task(path, preset, kinematics)  # a wrong kinematics: before anything is cancelled
        if self._runner is not None and self._runner.state == "running":
            self._runner.cancel()  # a newer choice replaces a load still running
        self._pending_session = session
        self.statusBar().showMessage(f"loading {what}…")
        # no modal dialog: the window stays usable; progress and Cancel sit in the status bar
        handlers = dict(on_done=self._on_loaded, on_error=self._on_load_error,
                        on_cancel=lambda: self.statusBar().showMessage("loading cancelled", 5000))
        if started is None:
            self._runner = run_task(task, parent=self, title=f"Loading {what}", dialog=False, **handlers)
        else:
            self._runner = connect_outcome(started, parent=self, **handlers)
        attach_status_progress(self, self._runner, f"loading {what}")
        if started is not None:  # what it reported while the window was built (its outcome too): before the first paint
            QtCore.QCoreApplication.sendPostedEvents(started)
        return self._runner

    def _on_loaded(self, result):
        from app.models.trajectories import stale_choice_note

        manifold, source = result
        self.set_manifold(manifold, source=source)
        if source.get("path"):
            self.settings.add_recent(source["path"])
            self._fill_recent_menu()
        warned = self._runner.warnings
        # a file whose stored synthesis choice older code measured: say what the first synthesis will cost
        stale = stale_choice_note(manifold, Path(source["path"]).name, short=True) if source.get("path") else None
        if warned:  # e.g. a disconnected state graph: keep it on screen, not "ready"
            self.statusBar().showMessage(f"loaded with a warning: {warned[-1]}", 30000)
        elif stale is not None:
            self.statusBar().showMessage(stale, 30000)
        else:
            self.statusBar().showMessage("ready", 3000)
        if self._pending_session is not None:
            d, self._pending_session = self._pending_session, None
            # a session that does not fit what was loaded: a dialog, not a traceback in the slot
            self._report(lambda: self.apply_session(d), "session restored", "restore the session")

    def _on_load_error(self, message, _tb):
        self.statusBar().showMessage("loading failed", 5000)
        self.show_error(message)

    def show_error(self, message: str) -> None:
        """A plain-language error dialog (``message`` from :func:`app.user_messages.user_message`)."""
        self.last_error_message = message
        box = QtWidgets.QMessageBox(QtWidgets.QMessageBox.Icon.Critical, "Lipspace", message,
                                    QtWidgets.QMessageBox.StandardButton.Ok, self)
        box.setObjectName("error_dialog")
        box.setAttribute(QtCore.Qt.WidgetAttribute.WA_DeleteOnClose)
        box.open()

    def open_dialog(self):
        path, _ = QtWidgets.QFileDialog.getOpenFileName(
            self, "Open corpus or manifold", self.last_dir,
            "Lipspace files (*.npz);;Motion data (*.mat *.ema *.c3d *.csv *.npy);;All files (*)")
        if path:
            self.last_dir = str(Path(path).parent)
            self.open_source(path)

    def _report(self, fn, ok_message, doing="finish that"):
        from app.user_messages import user_message

        try:
            fn()
        except (ValueError, OSError, RuntimeError, KeyError, IndexError, TypeError, MemoryError) as exc:
            self.show_error(user_message(exc, doing=doing))
            return False
        self.statusBar().showMessage(ok_message, 5000)
        return True

    # ------------------------------------------------------------------ misc
    def reset_cameras(self):
        self.manifold_view.standard_view("default")  # both halves of the manifold, the plane slightly from above
        self.lip_view.reset_camera()

    #: the docks' first sizes (pixels), given at construction and again by View > Reset layout:
    #: (docks, their sizes, the direction measured)
    #: (the editor's dock is fitted to what the editor shows instead: _fit_editor_dock)
    DOCK_SIZES = ((("lips",), (480,), QtCore.Qt.Orientation.Horizontal),
                  (("lips", "clusters"), (380, 420), QtCore.Qt.Orientation.Vertical))
    #: below this window height the editor's tiers and sound are drawn lower (a laptop's screen)
    COMPACT_BELOW = 900

    def resizeEvent(self, event):
        super().resizeEvent(event)
        self.editor.set_compact(self.height() < self.COMPACT_BELOW)

    def _size_docks(self) -> None:
        for keys, sizes, direction in self.DOCK_SIZES:
            self.resizeDocks([self.docks[k] for k in keys], list(sizes), direction)

    def say_once(self, message: str, ms: int = 15000) -> bool:
        """Show ``message`` in the status bar, unless it was said already in this window (returns whether it was
        shown)."""
        if message in self._said:
            return False
        self._said.add(message)
        self.statusBar().showMessage(message, ms)
        return True

    def _check_sound(self, playing: bool) -> None:
        """Playback with a sound the machine cannot play: why, once."""
        from app.files.sound import playback_audio

        audio = self.lip_view.audio
        if playing and not audio.available and playback_audio(self.state) is not None:
            self.say_once(f"no sound: {audio.reason}; the lips play silent")

    def _fit_editor_dock(self, height: int | None = None) -> None:
        """Give the editor's dock the height its contents need (``height``: the editor's size hint)."""
        dock = self.docks["editor"]
        if dock.isFloating() or not dock.isVisible() and self.isVisible():
            return
        want = height if height is not None else self.editor.needed_height()
        title = 0  # the title bar stands on the dock's side (DockWidgetVerticalTitleBar): no height
        if not dock.features() & QtWidgets.QDockWidget.DockWidgetFeature.DockWidgetVerticalTitleBar:
            title = max(dock.height() - dock.widget().height(), dock.fontMetrics().height() + 6)
        self.resizeDocks([dock], [max(int(want), self.editor.minimumHeight()) + title],
                         QtCore.Qt.Orientation.Vertical)

    def reset_layout(self) -> None:
        """View > Reset layout: every dock back where it started, shown, at its first size."""
        for dock in self.docks.values():
            dock.setFloating(False)
            dock.show()
        self.restoreState(self._default_layout)
        self._size_docks()
        self._fit_editor_dock()

    def closeEvent(self, event):
        from app.workers import cancel_all

        self.settings.save_layout(self)
        for box in self.findChildren(QtWidgets.QMessageBox):  # error dialogs left open go with the window
            box.close()
        if self._help is not None:
            self._help.close()
        self._autosave_timer.stop()
        cancel_all()
        self._close_condition_views()
        for view in (self.manifold_view, self.lip_view, self.editor, self.clusters, self.scree):
            view.close_view()
        super().closeEvent(event)
