"""Edit › Undo and Redo of the main window: the editor's target edits and the view's settings, in one history.

The trajectory editor keeps its edits of the key targets on its own stack (Load starts its
history anew); the view's settings (colour mode, hemisphere, horizon, phone filter, path mode,
ellipsoids and their opacity, hidden layers: :data:`app.models.state.fields.SETTINGS`) are
recorded on another from the state's ``settings`` event, one command per action (a slider
drag merges into one). Edit › Undo undoes the most recent edit of either, Redo redoes the
most recently undone: one history, in the order the user made the edits.
"""
from __future__ import annotations

import itertools

import shiboken6
from PySide6 import QtCore, QtGui

__all__ = ["ViewSettingsEdit", "SettingsRecorder", "History", "settings_text"]

_ORDER = itertools.count(1)

#: the words an undo command uses for each setting
SETTING_NAMES = {"hemisphere": "hemisphere", "horizon_ms": "horizon", "color_mode": "colouring",
                 "phone_filter": "phone filter", "path_mode": "path mode", "visible_phones": "ellipsoids",
                 "ellipsoid_opacity": "ellipsoid fill", "hidden_layers": "layers shown"}
#: settings whose consecutive changes (a slider dragged) merge into one command
_MERGED = ("horizon_ms", "ellipsoid_opacity")


def settings_text(before: dict, after: dict) -> str:
    """How Edit › Undo names a change of view settings ("colouring: phone", "horizon, colouring")."""
    names = [SETTING_NAMES.get(k, k) for k in after]
    if len(after) == 1 and "color_mode" in after:
        return f"colouring by {after['color_mode']}"
    if len(after) > 3:
        return "view settings"
    return ", ".join(names)


class ViewSettingsEdit(QtGui.QUndoCommand):
    """One change of the view's settings: ``before`` and ``after`` dicts of the settings it changed."""

    def __init__(self, recorder, before: dict, after: dict):
        super().__init__(settings_text(before, after))
        self.recorder, self.before, self.after = recorder, dict(before), dict(after)
        self._done = True  # pushed after the state changed: the first redo has nothing to do

    def redo(self):
        if self._done:
            self._done = False
            return
        self.recorder.replay(self.after)

    def undo(self):
        self.recorder.replay(self.before)

    def id(self) -> int:  # noqa: A003 - Qt's name
        keys = tuple(self.after)
        return 1 + _MERGED.index(keys[0]) if len(keys) == 1 and keys[0] in _MERGED else -1

    def mergeWith(self, other) -> bool:  # noqa: N802 - Qt's name
        if other.id() != self.id() or set(other.after) != set(self.after):
            return False
        self.after = dict(other.after)
        return True


class SettingsRecorder:
    """Pushes each action's change of the view settings (``state.events.settings``) on ``stack``.

    A new manifold clears the stack (its settings start anew); :meth:`replay` applies an undo's or
    a redo's values without recording them again.
    """

    def __init__(self, state, stack):
        self.state, self.stack = state, stack
        self.replaying = False
        state.events.settings.connect(self._on_settings)
        state.events.manifold.connect(lambda _m: stack.clear())

    def _on_settings(self, before, after) -> None:
        if not self.replaying:
            self.stack.push(ViewSettingsEdit(self, before, after))

    def replay(self, values: dict) -> None:
        self.replaying = True
        try:
            self.state.apply_settings(values)
        finally:
            self.replaying = False


class History(QtCore.QObject):
    """Undo / Redo over several QUndoStacks in the order their commands were made.

    Each command is stamped when it lands on its stack; Undo undoes the stack whose next
    undo is the newest, Redo redoes the stack whose next redo was undone last.
    """

    def __init__(self, stacks, parent=None):
        super().__init__(parent)
        self.stacks = list(stacks)
        self._undone = itertools.count(1)
        self.undo_action = QtGui.QAction("&Undo", parent)
        self.redo_action = QtGui.QAction("&Redo", parent)
        self.undo_action.triggered.connect(self.undo)
        self.redo_action.triggered.connect(self.redo)
        for st in self.stacks:
            st.indexChanged.connect(lambda _i, s=st: self._on_index(s))
            st.cleanChanged.connect(lambda _c, s=st: self._on_index(s))
        self._refresh()

    def _live(self) -> list:
        """The stacks still alive (a window being closed deletes its views' stacks first)."""
        return [st for st in self.stacks if shiboken6.isValid(st)]

    def _on_index(self, stack) -> None:
        if not shiboken6.isValid(stack) or not shiboken6.isValid(self.undo_action):
            return
        i = stack.index()
        if i > 0 and getattr(stack.command(i - 1), "_made", None) is None:  # a new command: stamp it
            stack.command(i - 1)._made = next(_ORDER)
        self._refresh()

    def _next_undo(self):
        best = None
        for st in self._live():
            if st.canUndo():
                made = getattr(st.command(st.index() - 1), "_made", 0) or 0
                if best is None or made > best[0]:
                    best = (made, st)
        return None if best is None else best[1]

    def _next_redo(self):
        best = None
        for st in self._live():
            if st.canRedo():
                undone = getattr(st.command(st.index()), "_undone", 0) or 0
                if best is None or undone > best[0]:
                    best = (undone, st)
        return None if best is None else best[1]

    def undo(self) -> bool:
        st = self._next_undo()
        if st is None:
            return False
        st.command(st.index() - 1)._undone = next(self._undone)
        st.undo()
        return True

    def redo(self) -> bool:
        st = self._next_redo()
        if st is None:
            return False
        st.redo()
        return True

    def _refresh(self) -> None:
        u, r = self._next_undo(), self._next_redo()
        self.undo_action.setEnabled(u is not None)
        self.redo_action.setEnabled(r is not None)
        self.undo_action.setText("&Undo" + (f" {u.undoText()}" if u is not None else ""))
        self.redo_action.setText("&Redo" + (f" {r.redoText()}" if r is not None else ""))
