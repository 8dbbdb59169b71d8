"""The main window's menus: File (open, recent files, the synthetic talkers, sessions, exports), Edit, View, Help."""
from __future__ import annotations

import functools
from pathlib import Path

from PySide6 import QtGui, QtWidgets

__all__ = ["MenuActions"]


def _raise_if_shown(dock, *_checked) -> None:
    if not dock.isHidden():  # once the layout has placed it: raised at once, it went back behind the tab in front
        from PySide6 import QtCore

        QtCore.QTimer.singleShot(0, dock.raise_)


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
        from app.figures import DESCRIPTIONS  # the names alone: no matplotlib until a figure is made

        for name, description in DESCRIPTIONS.items():
            a = self._act(exp, f"{name}: {description[:60]}…", lambda _=False, n=name: self.export_figure_dialog(n))
            a.setToolTip(description)
        self._act(f, "Export &trajectory (CSV, NPY, OBJ, PLY)…", self.export_trajectory_dialog)
        self._act(f, "Export synthesis as TextGrid…", self.export_textgrid_dialog)
        self._act(f, "Export &animation (glTF, MP4)…", self.export_animation_dialog)
        self._act(f, "Export &cluster table (CSV)…", self.export_clusters_dialog)
        self._act(f, "Export frame ta&ble (CSV, Parquet)…", self.export_frame_table_dialog)
        self._act(f, "Export Te&xtGrids (one per utterance)…", self.export_textgrids_dialog)
        f.addSeparator()
        self._act(f, "&Quit", self.close, QtGui.QKeySequence.StandardKey.Quit)
        e = mb.addMenu("&Edit")
        # one history: the editor's target edits and the view's settings, in the order they were made
        from app.window.undo import History

        self.history = History([self.editor.undo_stack, self.editor.gesture_undo_stack, self.view_undo_stack],
                               parent=self)
        self.undo_action, self.redo_action = self.history.undo_action, self.history.redo_action
        self.undo_action.setShortcut(QtGui.QKeySequence.StandardKey.Undo)
        self.redo_action.setShortcuts([QtGui.QKeySequence("Ctrl+Shift+Z"), QtGui.QKeySequence("Ctrl+Y")])
        e.addAction(self.undo_action)
        e.addAction(self.redo_action)
        v = mb.addMenu("&View")
        for dock in self.docks.values():
            v.addAction(dock.toggleViewAction())
            # shown from the menu, a dock comes to the front of its tab group (not behind the one in front)
            dock.toggleViewAction().triggered.connect(functools.partial(_raise_if_shown, dock))
        v.addSeparator()
        self.frame_action = self._act(v, "&Frame the selection", self.manifold_view.frame_selection,
                                      QtGui.QKeySequence("F"))
        self.frame_action.setToolTip("Bring the ticked clusters and the selection into view (F)")
        self.clear_selection_action = self._act(v, "&Clear the selection", self.state.clear_selection)
        self.clear_selection_action.setToolTip("Esc in the manifold view")
        layers = v.addMenu("Show in the 3-D view")
        self.layer_actions = {}
        for key, text in (("points", "&Points"), ("plane", "Zero-velocity &plane"), ("axes", "&Axes (Y1-Y3, S, V)"),
                          ("legend", "&Legends")):
            a = layers.addAction(text)
            a.setCheckable(True)
            a.setChecked(key not in self.state.hidden_layers)
            a.toggled.connect(lambda on, k=key: self.state.set_layer_visible(k, on))
            self.layer_actions[key] = a
        self.state.events.hidden_layers.connect(self._sync_layer_actions)
        self.reset_settings_action = self._act(v, "Reset view &settings", self.state.reset_settings)
        self.reset_settings_action.setToolTip("Colouring, hemisphere, horizon, phone filter, ellipsoids and layers "
                                              "back to their defaults (undo with Ctrl+Z); the selection stays")
        self._act(v, "Reset 3-D cameras", self.reset_cameras)
        self._act(v, "Reset &layout", self.reset_layout)
        h = mb.addMenu("&Help")
        self._act(h, "&User guide", self.show_user_guide, QtGui.QKeySequence.StandardKey.HelpContents)
        self._act(h, "&Keyboard shortcuts", self.show_shortcuts)
        self._act(h, "&About Lipspace", self._about)

    def _sync_layer_actions(self, hidden) -> None:
        for key, a in self.layer_actions.items():
            a.blockSignals(True)
            a.setChecked(key not in hidden)
            a.blockSignals(False)

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
