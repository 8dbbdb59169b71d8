"""The main window's sessions: save, open, restore, and the autosave tick."""
from __future__ import annotations

from pathlib import Path

from PySide6 import QtWidgets

__all__ = ["SessionActions"]


class SessionActions:
    """Sessions of :class:`app.main_window.MainWindow` (a mixin): what a session file holds of the window."""

    def cameras(self) -> dict:
        return {"manifold": self.manifold_view.camera(), "lips": self.lip_view.camera()}

    def save_session(self, path) -> Path:
        from app.files.session import save_session

        return save_session(self.state, path, cameras=self.cameras(), extra=self.session_extra(),
                            targets=self.editor.targets)

    def session_extra(self) -> dict:
        """The views' settings a session keeps beside the state: the editor's, its signals', the Compare panel's."""
        extra = {"editor": self.editor.settings(), "signals": self.editor.signals_settings()}
        compare = getattr(self, "compare_panel", None)
        if compare is not None:
            extra["compare"] = compare.settings()
        return extra

    def _autosave_tick(self):
        """Timer slot: save the session once it has been unchanged for the autosave delay."""
        from app.files.autosave import session_fingerprint

        a = self.autosaver
        if a is None or self._pending_session is not None or self.state.manifold is None:
            return
        fp = session_fingerprint(self.state, cameras=self.cameras(), extra=self.session_extra(),
                                 targets=self.editor.targets)
        if not a.tick(fp, self.save_session) and a.last_error:
            self.statusBar().showMessage(a.last_error, 10000)

    def apply_session(self, d: dict) -> None:
        """Restore selection, modes, phones, editor settings and cameras from a loaded session."""
        from app.files.session import apply_session

        targets = apply_session(self.state, d)
        extra = d.get("extra", {})
        self.editor.apply_settings(extra.get("editor", {}))
        self.editor.apply_signals_settings(extra.get("signals"))
        compare = getattr(self, "compare_panel", None)
        if compare is not None and extra.get("compare"):
            compare.apply_settings(extra["compare"])
        if targets is not None:  # the editor's (edited) key targets, and its word tier
            from engine.recordings.corpus import PhoneInterval

            words = d.get("extra", {}).get("editor", {}).get("words") or []
            self.editor.restore_targets(targets, words=tuple(PhoneInterval(float(a), float(b), str(w))
                                                            for a, b, w in words))
        cams = d.get("cameras", {})
        if "manifold" in cams:
            self.manifold_view.set_camera(cams["manifold"])
        if "lips" in cams:
            self.lip_view.set_camera(cams["lips"])
        self.view_undo_stack.clear()  # a session is a document of its own: nothing of before to undo

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
