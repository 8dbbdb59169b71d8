"""The explorer's main window: the manifold view in the centre, the other views docked around it.

Every view observes one :class:`app.models.state.AppState`; the window only wires menus,
loading (in a worker thread with a progress dialog), sessions and exports.
"""
from __future__ import annotations

import contextlib
import signal
import sys
import threading
from pathlib import Path

from PySide6 import QtCore, QtGui, QtWidgets

from app.models.state import AppState

__all__ = ["MainWindow", "launch", "stop_on_signals"]

#: File > Export dialogs' filters; the suffixes each writes are read from them (app.figures.export.filter_suffixes)
TRAJECTORY_FILTERS = "CSV table (*.csv);;NumPy array (*.npy);;OBJ mesh sequence (*.obj);;PLY mesh sequence (*.ply)"
ANIMATION_FILTERS = "glTF binary (*.glb);;glTF (*.gltf);;MP4 video (*.mp4)"
FIGURE_FILTERS = "PNG image (*.png);;SVG (*.svg);;PDF (*.pdf)"

#: signals that stop the explorer from its terminal or the desktop session (Ctrl-C, kill, logout)
STOP_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")
#: how often the event loop hands control to Python so that a stop signal's handler runs (ms)
SIGNAL_POLL_MS = 200


# ============================================================================ the window
class MainWindow(QtWidgets.QMainWindow):
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
        self.tabifyDockWidget(self.docks["clusters"], self.docks["scree"])
        self.docks["clusters"].raise_()
        self._size_docks()
        self._set_minimum_sizes()
        self._default_layout = self.saveState()  # View > Reset layout goes back to this

        self.summary_label = QtWidgets.QLabel("no manifold loaded")
        self.statusBar().addPermanentWidget(self.summary_label)
        self._make_menus()
        self.state.events.manifold.connect(self._on_manifold)
        self.autosaver = autosave
        self._autosave_timer = QtCore.QTimer(self)
        self._autosave_timer.timeout.connect(self._autosave_tick)
        if autosave is not None:
            self._autosave_timer.start(1000)
        self.layout_restored = self.settings.restore_layout(self)
        if manifold is not None:
            self.set_manifold(manifold, source=source)

    #: smallest useful size of each view: below it the window stops shrinking instead of
    #: collapsing a dock to nothing (the Lips dock vanished at 1179 x 407 before)
    VIEW_MINIMUM = {"manifold": (360, 260), "lips": (240, 170), "clusters": (240, 150), "scree": (240, 150),
                    "editor": (560, 190)}

    def _set_minimum_sizes(self) -> None:
        views = {"manifold": self.manifold_view, **{k: d.widget() for k, d in self.docks.items()}}
        for key, view in views.items():
            hint = view.minimumSizeHint()  # never below what the view's own layout needs
            view.setMinimumSize(max(self.VIEW_MINIMUM[key][0], hint.width()),
                                max(self.VIEW_MINIMUM[key][1], hint.height()))
        self.setMinimumSize(self.minimumSizeHint())

    # ------------------------------------------------------------------ menus
    #: File > Open synthetic talker: (preset, kinematics) in menu order. The calibrated talker
    #: (lips that move as real articulograph sensors do) at the quick and the default size; the
    #: paper preset reproduces the paper's resolution with the classic talker only.
    SYNTHETIC_TALKERS = (("small", "classic"), ("default", "classic"), ("paper", "classic"),
                         ("small", "calibrated"), ("default", "calibrated"))

    @staticmethod
    def _talker_menu_text(preset: str, kinematics: str) -> str:
        from app.files.source_loading import KINEMATICS_LABELS

        return preset if kinematics == "classic" else f"{preset}, {KINEMATICS_LABELS[kinematics]}"

    @staticmethod
    def _talker_tooltip(preset: str, kinematics: str) -> str:
        size = {"small": "75 s, 156 points: quick", "default": "8 minutes, 600 points",
                "paper": "28,833 frames, 4,260 points: the paper's resolution"}[preset]
        if kinematics == "classic":
            return f"The synthetic talker ({size})."
        return (f"The synthetic talker ({size}) whose jaw, upper lip and corners move as real speakers' "
                "articulograph sensors do (opt-in); compare it with the classic talker above.")

    def _make_menus(self):
        mb = self.menuBar()
        f = mb.addMenu("&File")
        self._act(f, "&Open corpus or manifold…", self.open_dialog, QtGui.QKeySequence.StandardKey.Open)
        self.recent_menu = f.addMenu("Open &Recent")
        self.recent_menu.aboutToShow.connect(self._fill_recent_menu)
        self._fill_recent_menu()
        syn = f.addMenu("Open synthetic talker")
        syn.setToolTipsVisible(True)
        self.synthetic_actions = {}
        previous = self.SYNTHETIC_TALKERS[0][1]
        for preset, kinematics in self.SYNTHETIC_TALKERS:
            if kinematics != previous:
                syn.addSeparator()  # the calibrated talkers below the classic ones
            previous = kinematics
            a = self._act(syn, self._talker_menu_text(preset, kinematics),
                          lambda _=False, p=preset, k=kinematics: self.open_source(None, preset=p, kinematics=k))
            a.setToolTip(self._talker_tooltip(preset, kinematics))
            self.synthetic_actions[preset, kinematics] = a
        f.addSeparator()
        self._act(f, "&Save session…", self.save_session_dialog, QtGui.QKeySequence.StandardKey.Save)
        self._act(f, "Open s&ession…", self.open_session_dialog)
        f.addSeparator()
        exp = f.addMenu("Export &figure")
        self._act(exp, "Manifold view (PNG, SVG, PDF)…", lambda: self.export_view_dialog("manifold"))
        self._act(exp, "Lip view (PNG, SVG, PDF)…", lambda: self.export_view_dialog("lips"))
        exp.addSeparator()
        try:
            from app.figures import DESCRIPTIONS, FIGURES
        except ImportError:
            FIGURES, DESCRIPTIONS = {}, {}
        for name in FIGURES:
            a = self._act(exp, f"{name}: {DESCRIPTIONS.get(name, '')[:60]}…",
                          lambda _=False, n=name: self.export_figure_dialog(n))
            a.setToolTip(DESCRIPTIONS.get(name, ""))
        self._act(f, "Export &trajectory (CSV, NPY, OBJ, PLY)…", self.export_trajectory_dialog)
        self._act(f, "Export &animation (glTF, MP4)…", self.export_animation_dialog)
        self._act(f, "Export &cluster table (CSV)…", self.export_clusters_dialog)
        self._act(f, "Export frame ta&ble (CSV, Parquet)…", self.export_frame_table_dialog)
        self._act(f, "Export Te&xtGrids (one per utterance)…", self.export_textgrids_dialog)
        f.addSeparator()
        self._act(f, "&Quit", self.close, QtGui.QKeySequence.StandardKey.Quit)
        e = mb.addMenu("&Edit")
        stack = self.editor.undo_stack
        self.undo_action = stack.createUndoAction(self, "&Undo")
        self.undo_action.setShortcut(QtGui.QKeySequence.StandardKey.Undo)
        self.redo_action = stack.createRedoAction(self, "&Redo")
        self.redo_action.setShortcuts([QtGui.QKeySequence("Ctrl+Shift+Z"), QtGui.QKeySequence("Ctrl+Y")])
        e.addAction(self.undo_action)
        e.addAction(self.redo_action)
        v = mb.addMenu("&View")
        for key, dock in self.docks.items():
            v.addAction(dock.toggleViewAction())
        v.addSeparator()
        self._act(v, "Reset 3-D cameras", self.reset_cameras)
        self._act(v, "Reset &layout", self.reset_layout)
        h = mb.addMenu("&Help")
        self._act(h, "&User guide", self.show_user_guide, QtGui.QKeySequence.StandardKey.HelpContents)
        self._act(h, "&Keyboard shortcuts", self.show_shortcuts)
        self._act(h, "&About Lipspace", self._about)

    def _act(self, menu, text, slot, shortcut=None):
        a = QtGui.QAction(text, self)
        if shortcut is not None:
            a.setShortcut(shortcut)
        a.triggered.connect(slot)
        menu.addAction(a)
        return a

    def _fill_recent_menu(self):
        menu = self.recent_menu
        menu.clear()
        files = self.settings.recent_files()
        for i, path in enumerate(files):
            a = menu.addAction(f"&{i + 1} {Path(path).name}" if i < 9 else Path(path).name)
            a.setToolTip(path)
            a.setData(path)
            a.triggered.connect(lambda _=False, p=path: self.open_recent(p))
        if files:
            menu.addSeparator()
            menu.addAction("Clear list", self._clear_recent)
        else:
            menu.addAction("(no recent files)").setEnabled(False)

    def _clear_recent(self):
        self.settings.clear_recent()
        self._fill_recent_menu()

    def open_recent(self, path):
        """Open a file of File > Open Recent; a file since moved or deleted is taken off the list."""
        if not Path(path).is_file():
            self.settings.remove_recent(path)
            self._fill_recent_menu()
            self.show_error(f"{Path(path).name} is no longer there ({path}); it was taken off the recent files.")
            return None
        self.last_dir = str(Path(path).parent)
        return self.open_source(path)

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
                    session: dict | None = None):
        """Load a manifold / corpus file (or the synthetic talker ``preset`` with ``kinematics``,
        ``"classic"`` or ``"calibrated"``) in a worker; returns the runner."""
        from app.files.source_loading import check_kinematics, load_source, talker_name
        from app.user_messages import plain_errors
        from app.views.task_progress import attach_status_progress
        from app.workers import run_task

        check_kinematics(kinematics)  # a programming error, before anything is cancelled or started
        if self._runner is not None and self._runner.state == "running":
            self._runner.cancel()  # a newer choice replaces a load still running
        self._pending_session = session
        what = Path(path).name if path else f"the {talker_name(preset, kinematics)}"
        self.statusBar().showMessage(f"loading {what}…")
        # no modal dialog: the window stays usable; progress and Cancel sit in the status bar
        task = plain_errors(lambda progress: load_source(path, preset, progress, kinematics=kinematics),
                            doing=f"open {what}", path=path)
        self._runner = run_task(task, parent=self,
                                title=f"Loading {what}", on_done=self._on_loaded, on_error=self._on_load_error,
                                on_cancel=lambda: self.statusBar().showMessage("loading cancelled", 5000),
                                dialog=False)
        attach_status_progress(self, self._runner, f"loading {what}")
        return self._runner

    def _on_loaded(self, result):
        manifold, source = result
        self.set_manifold(manifold, source=source)
        if source.get("path"):
            self.settings.add_recent(source["path"])
            self._fill_recent_menu()
        warned = self._runner.warnings
        if warned:  # e.g. a disconnected state graph: keep it on screen, not "ready"
            self.statusBar().showMessage(f"loaded with a warning: {warned[-1]}", 30000)
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

    # ------------------------------------------------------------------ sessions
    def cameras(self) -> dict:
        return {"manifold": self.manifold_view.camera(), "lips": self.lip_view.camera()}

    def save_session(self, path) -> Path:
        from app.files.session import save_session

        return save_session(self.state, path, cameras=self.cameras(), extra={"editor": self.editor.settings()},
                            targets=self.editor.targets)

    def _autosave_tick(self):
        """Timer slot: save the session once it has been unchanged for the autosave delay."""
        from app.files.autosave import session_fingerprint

        a = self.autosaver
        if a is None or self._pending_session is not None or self.state.manifold is None:
            return
        fp = session_fingerprint(self.state, cameras=self.cameras(), extra={"editor": self.editor.settings()},
                                 targets=self.editor.targets)
        if not a.tick(fp, self.save_session) and a.last_error:
            self.statusBar().showMessage(a.last_error, 10000)

    def apply_session(self, d: dict) -> None:
        """Restore selection, modes, phones, editor settings and cameras from a loaded session."""
        from app.files.session import apply_session

        targets = apply_session(self.state, d)
        self.editor.apply_settings(d.get("extra", {}).get("editor", {}))
        if targets is not None:  # the editor's (edited) key targets
            self.editor.restore_targets(targets)
        cams = d.get("cameras", {})
        if "manifold" in cams:
            self.manifold_view.set_camera(cams["manifold"])
        if "lips" in cams:
            self.lip_view.set_camera(cams["lips"])

    def open_session(self, path):
        """Open a session file: reload its source if it differs from what is shown, then restore it."""
        from app.files.session import load_session, source_kinematics

        d = load_session(path)
        src, cur = d.get("source", {}), self.state.source
        same = self.state.manifold is not None and src.get("path") == cur.get("path") and (
            src.get("path") is not None or (src.get("preset") == cur.get("preset") and
                                            src.get("kinematics", "classic") == cur.get("kinematics", "classic")))
        if same:
            self.apply_session(d)
            return None
        return self.open_source(src.get("path"), preset=src.get("preset", "default"),
                                kinematics=source_kinematics(d), session=d)

    def save_session_dialog(self):
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Save session", self.last_dir,
                                                        "Lipspace session (*.lipspace.json *.json)")
        if path:
            if not path.endswith(".json"):
                path += ".lipspace.json"
            self._report(lambda: self.save_session(path), f"session saved to {path}", "save the session")

    def open_session_dialog(self):
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self, "Open session", self.last_dir,
                                                        "Lipspace session (*.json);;All files (*)")
        if path:
            self._report(lambda: self.open_session(path), f"session {Path(path).name} opened", "open the session")

    def _report(self, fn, ok_message, doing="finish that"):
        from app.user_messages import user_message

        try:
            fn()
        except (ValueError, OSError, RuntimeError, KeyError, IndexError, TypeError, MemoryError) as exc:
            self.show_error(user_message(exc, doing=doing))
            return False
        self.statusBar().showMessage(ok_message, 5000)
        return True

    # ------------------------------------------------------------------ exports
    def _view_plotter(self, which: str):
        """The plotter of the ``"manifold"`` or ``"lips"`` view."""
        return {"manifold": self.manifold_view.plotter, "lips": self.lip_view.plotter}[which]

    def export_view(self, which: str, path, *, dpi=None) -> Path:
        """Save the manifold or lip view as PNG (at ``dpi``) or SVG/PDF (vector, from the scene's data)."""
        from app.figures import save_plotter_image, save_plotter_vector

        plotter = self._view_plotter(which)
        if Path(path).suffix.lower() == ".png":
            return save_plotter_image(plotter, path, dpi=dpi)
        return save_plotter_vector(plotter, path)

    def _save_path(self, title: str, filters: str, start: str | None = None) -> Path | None:
        """Ask where to save (None: cancelled). A name typed without one of the suffixes ``filters``
        names takes the chosen filter's, so every File > Export dialog reads a typed name alike."""
        from app.figures.export import filter_suffixes, suffix_from_filter

        path, chosen = QtWidgets.QFileDialog.getSaveFileName(self, title, self.last_dir if start is None else start,
                                                             filters)
        return suffix_from_filter(path, chosen, filter_suffixes(filters)) if path else None

    def export_view_dialog(self, which):
        path = self._save_path(f"Export {which} view", FIGURE_FILTERS)
        if path:
            dpi = None
            if path.suffix.lower() == ".png":
                dpi, ok = QtWidgets.QInputDialog.getInt(self, "PNG resolution", "Dots per inch (96 = as on screen):",
                                                        150, 30, 1200, 10)
                if not ok:
                    return
                self._report(lambda: self.export_view(which, path, dpi=dpi), f"wrote {path}",
                             f"export the {which} view")
                return
            # vector: the scene is read here (VTK, GUI thread); writing the file, most of the time, runs in a worker
            from app.figures.export import save_vector_figure
            from app.figures.view_vector import scene_figure
            from app.user_messages import plain_errors
            from app.workers import run_task

            fig = scene_figure(self._view_plotter(which))
            run_task(plain_errors(lambda progress: save_vector_figure(fig, path), doing=f"export the {which} view"),
                     parent=self, title=f"Writing {path.name}", dialog=False,
                     on_done=lambda p: self.statusBar().showMessage(f"wrote {p}", 5000))
            self.statusBar().showMessage(f"writing {path.name}…")

    def export_figure_dialog(self, name):
        if self.state.manifold is None:
            return
        path = self._save_path(f"Export figure {name}", FIGURE_FILTERS, str(Path(self.last_dir) / f"{name}.png"))
        if not path:
            return
        from app.figures import UTTERANCE_FIGURES, export_figure
        from app.user_messages import plain_errors
        from app.workers import run_task

        m = self.state.manifold
        opts = {"utterance": self.state.utterance} if (name in UTTERANCE_FIGURES and self.state.utterance) else {}
        run_task(plain_errors(lambda progress: export_figure(name, m, path, **opts), doing=f"write figure {name}"),
                 parent=self, title=f"Rendering {name}",
                 on_done=lambda p: self.statusBar().showMessage(f"wrote {p}", 5000))

    def current_trajectory(self):
        """The trajectory File > Export writes: the synthetic one if any, else the original."""
        return self.state.synthetic if self.state.synthetic is not None else self.state.original

    def export_trajectory_dialog(self):
        traj = self.current_trajectory()
        if traj is None:
            QtWidgets.QMessageBox.information(self, "Lipspace", "No trajectory to export: choose an utterance or "
                                                               "synthesise one in the trajectory editor.")
            return
        path = self._save_path(f"Export trajectory ({traj.label})", TRAJECTORY_FILTERS)
        if path:
            from app.models.trajectories import export_trajectory

            path = str(path)
            self._report(lambda: export_trajectory(self.state.manifold, traj, path), f"wrote {path}",
                         "export the trajectory")

    def export_animation(self, path, progress=None) -> list[Path]:
        """The current trajectory as a glTF morph animation (.glb/.gltf, WAV beside) or an MP4."""
        from app.export.current import export_current_animation

        return export_current_animation(self.state, path, progress=progress)

    def export_animation_dialog(self):
        path = self._save_path("Export animation", ANIMATION_FILTERS)
        if not path:
            return
        path = str(path)
        from engine.progress import Cancelled

        dlg = QtWidgets.QProgressDialog("Rendering the video…", "Cancel", 0, 100, self)
        dlg.setWindowModality(QtCore.Qt.WindowModality.WindowModal)

        def progress(_stage, done, total):  # off-screen VTK stays in the GUI thread
            dlg.setMaximum(total)
            dlg.setValue(done)
            QtWidgets.QApplication.processEvents()
            if dlg.wasCanceled():
                raise Cancelled("export cancelled")

        try:
            self._report(lambda: self.export_animation(path, progress), f"wrote {path}", "export the animation")
        except Cancelled:
            self.statusBar().showMessage("export cancelled; nothing was written", 5000)
        finally:
            dlg.close()

    def export_clusters(self, path) -> Path:
        from engine.io.writers.export import write_table_csv

        return write_table_csv(path, self.clusters.table_rows())

    def export_clusters_dialog(self):
        if self.state.manifold is None:
            return
        path = self._save_path("Export cluster table", "CSV table (*.csv)")
        if path:
            path = str(path)
            self._report(lambda: self.export_clusters(path), f"wrote {path}", "export the cluster table")

    def _source_name(self) -> str:
        return str(self.state.source.get("path") or f"synthetic talker ({self.state.source.get('preset')})")

    def export_frame_table_dialog(self):
        """One row per frame, as ``lipspace table -o`` writes it (units in a .json beside it), in a worker."""
        if self.state.manifold is None:
            return
        from app.export.tables import export_frame_table, table_filters

        path = self._save_path("Export frame table", table_filters(), str(Path(self.last_dir) / "frames.csv"))
        if not path:
            return
        from app.user_messages import plain_errors
        from app.workers import run_task

        m, src = self.state.manifold, self._source_name()
        run_task(plain_errors(lambda progress: export_frame_table(m, path, source=src, progress=progress),
                              doing="export the frame table"), parent=self, title=f"Writing {path.name}",
                 on_done=lambda paths: self.statusBar().showMessage(
                     f"wrote {paths[0]} (units in {paths[1].name})", 8000))

    def export_textgrids_dialog(self):
        """One TextGrid per utterance into a folder, as ``lipspace table --textgrid`` writes them, in a worker."""
        m = self.state.manifold
        if m is None:
            return
        from app.export.tables import existing_textgrids, export_textgrids

        folder = QtWidgets.QFileDialog.getExistingDirectory(self, "Export TextGrids into folder", self.last_dir)
        if not folder:
            return
        there = existing_textgrids(m, folder)
        if there and QtWidgets.QMessageBox.question(
                self, "Lipspace", f"{len(there)} of the TextGrids exist already in {folder} (e.g. {there[0].name}). "
                                  "Replace them?") != QtWidgets.QMessageBox.StandardButton.Yes:
            return
        from app.user_messages import plain_errors
        from app.workers import run_task

        src = self._source_name()
        run_task(plain_errors(lambda progress: export_textgrids(m, folder, source=src, progress=progress),
                              doing="export the TextGrids"), parent=self, title="Writing TextGrids",
                 on_done=lambda files: self.statusBar().showMessage(f"wrote {len(files)} TextGrids to {folder}", 8000))

    # ------------------------------------------------------------------ misc
    def reset_cameras(self):
        self.manifold_view.standard_view("default")  # both halves of the manifold, the plane slightly from above
        self.lip_view.plotter.view_xy()
        self.lip_view.plotter.reset_camera()
        self.lip_view.plotter.render()

    #: the docks' first sizes (pixels), given at construction and again by View > Reset layout:
    #: (docks, their sizes, the direction measured)
    DOCK_SIZES = ((("lips",), (480,), QtCore.Qt.Orientation.Horizontal),
                  (("lips", "clusters"), (420, 380), QtCore.Qt.Orientation.Vertical),
                  (("editor",), (230,), QtCore.Qt.Orientation.Vertical))

    def _size_docks(self) -> None:
        for keys, sizes, direction in self.DOCK_SIZES:
            self.resizeDocks([self.docks[k] for k in keys], list(sizes), direction)

    def reset_layout(self) -> None:
        """View > Reset layout: every dock back where it started, shown, at its first size."""
        for dock in self.docks.values():
            dock.setFloating(False)
            dock.show()
        self.restoreState(self._default_layout)
        self._size_docks()

    def _show_help(self, title, page):
        from app.help.browser import HelpBrowser

        if self._help is None:
            self._help = HelpBrowser(title, page, self)
        self._help.setWindowTitle(title)
        self._help.set_page(page)
        self._help.show()
        self._help.raise_()
        return self._help

    def show_user_guide(self):
        """Help > User guide: the guide shipped with the program, in a help window."""
        from app.help import user_guide_html

        return self._show_help("Lipspace user guide", user_guide_html())

    def show_shortcuts(self):
        from app.help import shortcut_sheet_html

        return self._show_help("Lipspace keyboard shortcuts", shortcut_sheet_html())

    def about_text(self) -> str:
        from app.help import about_html
        from engine import __version__

        return about_html(__version__)

    def _about(self):
        QtWidgets.QMessageBox.about(self, "About Lipspace", self.about_text())

    def closeEvent(self, event):
        from app.workers import cancel_all

        self.settings.save_layout(self)
        for box in self.findChildren(QtWidgets.QMessageBox):  # error dialogs left open go with the window
            box.close()
        if self._help is not None:
            self._help.close()
        self._autosave_timer.stop()
        cancel_all()
        for view in (self.manifold_view, self.lip_view, self.editor, self.clusters, self.scree):
            view.close_view()
        super().closeEvent(event)


def ask_restore(recovery, parent=None) -> str:
    """Ask whether to reopen a crashed run's autosave: "restore", "discard" or "later"."""
    box = QtWidgets.QMessageBox(parent)
    box.setIcon(QtWidgets.QMessageBox.Icon.Question)
    box.setWindowTitle("Lipspace")
    box.setText(recovery.describe())
    box.setInformativeText("Restore that session now?")
    yes = box.addButton("Restore", QtWidgets.QMessageBox.ButtonRole.AcceptRole)
    no = box.addButton("Discard", QtWidgets.QMessageBox.ButtonRole.DestructiveRole)
    box.addButton("Not now", QtWidgets.QMessageBox.ButtonRole.RejectRole)
    box.setDefaultButton(yes)
    box.exec()
    clicked = box.clickedButton()
    return "restore" if clicked is yes else "discard" if clicked is no else "later"


def launch(path=None, preset: str = "default", session: dict | None = None, restore: bool | None = None, *,
           kinematics: str = "classic", notes=()) -> int:
    """Open the explorer on ``path`` (or the synthetic talker ``preset`` with ``kinematics``)
    and run the event loop; a session's (or a restored autosave's) source overrides them.

    ``restore`` answers the autosave question after an abnormal exit (None: ask in a
    dialog); see :mod:`app.files.autosave`. Damaged state files (autosave markers and sessions,
    the window settings) are moved aside and said, on stderr and in one dialog, with
    ``notes`` (e.g. a --session file that could not be opened); the window opens anyway.
    """
    from app.files.autosave import Autosaver, resolve_recovery
    from app.files.session import SessionError, source_kinematics
    from app.qt_app import make_application
    from app.user_messages import user_message

    app = make_application(sys.argv[:1])
    autosaver = Autosaver()
    try:
        recovery = autosaver.begin()
    except OSError as exc:
        print(f"lipspace explore: warning: autosave is off ({autosaver.directory}: {exc})", file=sys.stderr)
        autosaver, recovery = None, None
    win = MainWindow(autosave=autosaver)
    signals = contextlib.ExitStack()  # from here on (the restore question too) a stop signal closes the window
    stopped = signals.enter_context(stop_on_signals(app, win))
    win.show()
    said = list(notes)
    for note in (autosaver.set_aside if autosaver is not None else []) + win.settings.set_aside:
        print(f"lipspace explore: warning: {note}", file=sys.stderr)
        said.append(note)
    if said:
        win.show_error("\n\n".join(said))
    if autosaver is not None and session is None:
        try:
            restored = resolve_recovery(autosaver, recovery, restore=restore, ask=lambda r: ask_restore(r, win))
        except SessionError as exc:
            print(f"lipspace explore: warning: {exc}", file=sys.stderr)
            win.show_error(user_message(exc, doing="restore the autosaved session"))  # not modal: the window runs
            restored = None
        if restored is not None:
            session, path = restored, None
    if session is not None and path is None and session.get("source", {}).get("path"):
        path = session["source"]["path"]
        preset = session["source"].get("preset", preset)
        kinematics = "classic"
    elif session is not None and path is None:
        preset = session.get("source", {}).get("preset", preset)
        kinematics = source_kinematics(session)
    code = 0
    if not stopped:  # else a signal came during the restore question: the window is closed already
        win.open_source(path, preset=preset, kinematics=kinematics, session=session)
        code = int(app.exec())
    signals.close()
    if stopped:
        # not a chosen Quit: no finish(), so a saved session (or a restored one not yet saved
        # again) stays and the next start offers it back; a marker without one is pruned then
        if autosaver is not None and autosaver.session.is_file():
            kept = "the session was autosaved and is offered back at the next start"
        else:
            kept = "nothing was autosaved yet" if autosaver is not None else "autosave is off"
        print(f"lipspace explore: stopped by {stopped[-1]}; the window was closed ({kept}).", file=sys.stderr)
        return 128 + int(getattr(signal, stopped[-1]))
    if autosaver is not None:
        autosaver.finish()  # a clean exit: nothing to offer next time
    return code


@contextlib.contextmanager
def stop_on_signals(app, win):
    """Ctrl-C in the terminal, SIGTERM or SIGHUP close ``win`` as File > Quit does and end the loop.

    Python runs a signal handler only between its own bytecodes, and the Qt event loop
    runs none while it waits: a timer hands control to Python every ``SIGNAL_POLL_MS``.
    The handler only notes the signal; the timer's slot saves the session to the
    autosave (when there is one and something is loaded), closes the window and quits,
    from the event loop, never from inside whatever slot the signal interrupted.
    Without this the command-line handler's ``KeyboardInterrupt`` was raised inside a
    Qt slot, printed as a traceback and swallowed: the window could not be stopped.

    Yields the list of signal names received (empty unless one stopped the window).
    Only in the main thread; the previous handlers are restored on exit.
    """
    stopped: list = []
    if threading.current_thread() is not threading.main_thread():
        yield stopped
        return

    def handler(signum, _frame):
        stopped.append(signal.Signals(signum).name)

    def poll():
        if not stopped or poll.done:
            return
        poll.done = True
        modal = QtWidgets.QApplication.activeModalWidget()
        if isinstance(modal, QtWidgets.QDialog):  # the restore question (or any dialog): answered "not now"
            modal.reject()
        a = win.autosaver
        if a is not None and win.state.manifold is not None:
            with contextlib.suppress(OSError, ValueError, RuntimeError):
                a.save(win.save_session)
        win.close()
        app.quit()

    poll.done = False
    old = {}
    for name in STOP_SIGNALS:
        sig = getattr(signal, name, None)
        if sig is not None:
            old[sig] = signal.signal(sig, handler)
    timer = QtCore.QTimer()
    timer.setInterval(SIGNAL_POLL_MS)
    timer.timeout.connect(poll)
    timer.start()
    try:
        yield stopped
    finally:
        timer.stop()
        for sig, h in old.items():
            signal.signal(sig, h)
