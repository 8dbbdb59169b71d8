"""The trajectory editor's undo commands: one edit of the key targets and of the tiers (phones, words)."""
from __future__ import annotations

from PySide6 import QtGui

__all__ = ["TargetsEdit"]


class TargetsEdit(QtGui.QUndoCommand):
    """One edit of the key targets (move, add, remove, reset) or of the tiers (a boundary moved), on the
    editor's undo stack. ``words_before`` / ``words_after`` are the word tiers (None: unchanged)."""

    def __init__(self, editor, before, after, text: str, words_before=None, words_after=None):
        super().__init__(text)
        self.editor, self.before, self.after = editor, before, after
        self.words_before, self.words_after = words_before, words_after

    def redo(self):
        self.editor._apply_targets(self.after, f"{self.text()}: press Synthesise", words=self.words_after)

    def undo(self):
        self.editor._apply_targets(self.before, f"undone: {self.text()}", words=self.words_before)
