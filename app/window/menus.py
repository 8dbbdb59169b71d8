"""The main window's menus: File (open, recent files, the synthetic talkers, sessions, exports), Edit, View, Help."""
from __future__ import annotations

from pathlib import Path

from PySide6 import QtGui, QtWidgets

__all__ = ["MenuActions"]


class MenuActions:
    """The menus of :class:`app.main_window.MainWindow` and what their plain entries do (a mixin)."""

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

    # ------------------------------------------------------------------ help
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
