"""Which sound the trajectory editor's :class:`app.views.sound_panel.SoundPanel` shows, computed off the GUI thread.

:class:`SoundTrack` resolves an utterance's audio file, computes its waveform and
spectrogram (:func:`engine.phonetics.spectrogram.sound_display`) in a worker thread
(:func:`app.workers.run_task`, no dialog), keeps the results of the last few
utterances (:data:`CACHE_SIZE`), and hands the panel the one asked for last; a
request for another utterance cancels the computation still running for the
previous one. Nothing here blocks the GUI thread: a click on the manifold is served
while a spectrogram is being computed.
"""
from __future__ import annotations

from collections import OrderedDict

from PySide6 import QtCore

__all__ = ["SoundTrack", "CACHE_SIZE"]

#: utterances whose waveform and spectrogram stay in memory (a 60-s one holds ~35 MB)
CACHE_SIZE = 8


class SoundTrack(QtCore.QObject):
    """Feeds a :class:`SoundPanel` the sound of the utterance the editor shows.

    .. rubric:: Signals

    changed(bool)
        Emitted when the panel gets a sound (True) or loses it (False).
    """

    changed = QtCore.Signal(bool)

    def __init__(self, panel, state, parent=None):
        super().__init__(parent)
        self.panel, self.state = panel, state
        self.cache: OrderedDict = OrderedDict()  # (utterance id, path) -> (SoundDisplay, grey)
        self.wanted = None  # (uid, path) asked for last, or None
        self.runner = None
        self.error = None

    @property
    def has_sound(self) -> bool:
        return self.panel.display is not None

    def clear_cache(self) -> None:
        """Forget every computed sound (a new manifold: its utterances are other recordings)."""
        self.cache.clear()
        self.show(None)

    def audio_path(self, uid):
        """The utterance's audio file, or None when it has none (or the file is missing)."""
        from app.audio import resolve_audio_path

        m = self.state.manifold
        if m is None or uid is None:
            return None
        try:
            u = m.corpus_.utterance(uid)
        except KeyError:
            return None
        return resolve_audio_path(u.audio, (self.state.source or {}).get("path"))

    def show(self, uid) -> bool:
        """Show utterance ``uid``'s sound (None: none). Returns True when it is shown at once
        (cached), False when it is being computed or there is none."""
        path = self.audio_path(uid)
        key = None if path is None else (uid, str(path))
        if key == self.wanted and (self.has_sound or self.runner is not None):
            return self.has_sound
        self.wanted, self.error = key, None
        self._cancel_running()
        if key is None:
            self._set(None, None, "")
            return False
        if key in self.cache:
            self.cache.move_to_end(key)
            self._set(*self.cache[key], "")
            return True
        self._set(None, None, "computing the spectrogram…")
        self._start(key, path)
        return False

    def _start(self, key, path):
        from app.user_messages import plain_errors
        from app.workers import run_task
        from engine.phonetics.spectrogram import sound_display

        def task(progress):
            disp = sound_display(path, progress=progress)
            return key, disp, disp.spectrogram.grey()

        self.runner = run_task(plain_errors(task, doing=f"read the sound {path.name}"), parent=self,
                               title="Spectrogram", dialog=False, on_done=self._on_done,
                               on_error=self._on_error, on_cancel=lambda: None)

    def _cancel_running(self):
        if self.runner is not None and self.runner.state == "running":
            self.runner.cancel()
        self.runner = None

    def _on_done(self, result):
        key, disp, grey = result
        self.cache[key] = (disp, grey)
        self.cache.move_to_end(key)
        while len(self.cache) > CACHE_SIZE:
            self.cache.popitem(last=False)
        if key == self.wanted:
            self.runner = None
            self._set(disp, grey, "")

    def _on_error(self, message, _tb=""):
        self.runner = None
        self.error = message
        self._set(None, None, f"no spectrogram: {message}")

    def _set(self, display, grey, message):
        had = self.has_sound
        self.panel.set_sound(display, grey, message)
        if had != self.has_sound or display is not None:
            self.changed.emit(self.has_sound)

    def stop(self) -> None:
        """Cancel a computation still running (the editor closes)."""
        self._cancel_running()
