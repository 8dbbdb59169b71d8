"""Audio playback of an utterance, guarded so a machine without sound never fails.

QtMultimedia (PySide6-Addons) needs system libraries (PulseAudio/ALSA) and an
output device; when either is missing :class:`AudioPlayer` reports
``available == False`` with a reason and every call is a no-op.
"""
from __future__ import annotations

from pathlib import Path

from app.files.sound import resolve_audio_path

__all__ = ["AudioPlayer", "resolve_audio_path"]


class AudioPlayer:
    """Plays WAV files through QtMultimedia when a device exists; otherwise does nothing.

    The device is looked for, and the player made, when sound is first asked for (``play``,
    ``available`` or ``reason``), not when the window is built: QtMultimedia's import and its
    backend's device query take tens of milliseconds that the window's first frame need not wait for.

    Attributes
    ----------
    available : bool
    reason : str
        Why audio is unavailable ('' when it is available).
    """

    def __init__(self, parent=None):
        self._parent = parent
        self._ready = False
        self._available, self._reason = False, ""
        self._player = self._output = None
        self._playing_state = None

    @property
    def available(self) -> bool:
        self._set_up()
        return self._available

    @property
    def reason(self) -> str:
        self._set_up()
        return self._reason

    def _set_up(self) -> None:
        """Find the output device and make the player, once."""
        if self._ready:
            return
        self._ready = True
        try:
            from PySide6.QtMultimedia import QAudioOutput, QMediaDevices, QMediaPlayer
        except ImportError as exc:  # missing libpulse / Addons
            self._reason = f"QtMultimedia cannot load ({exc})"
            return
        try:
            if not QMediaDevices.audioOutputs():
                self._reason = "no audio output device"
                return
            self._output = QAudioOutput(self._parent)
            self._player = QMediaPlayer(self._parent)
            self._player.setAudioOutput(self._output)
            self._playing_state = QMediaPlayer.PlaybackState.PlayingState
        except Exception as exc:  # noqa: BLE001 - any backend failure means no sound, not a crash
            self._reason = f"audio backend failed ({exc})"
            self._player = self._output = None
            return
        self._available = True

    def play(self, path, start_s: float = 0.0, rate: float = 1.0) -> bool:
        """Start playing ``path`` from ``start_s`` seconds; returns whether sound started."""
        if path is None or not self.available:
            return False
        from PySide6.QtCore import QUrl

        self._player.setSource(QUrl.fromLocalFile(str(Path(path).resolve())))
        self._player.setPlaybackRate(float(rate))
        self._player.setPosition(int(1000 * start_s))
        self._player.play()
        return True

    def set_rate(self, rate: float) -> None:
        """Change the playback speed of the sound that plays (media seconds per second)."""
        if self._available:  # nothing plays before the player is made
            self._player.setPlaybackRate(float(rate))

    def position_s(self) -> float | None:
        """Where the sound is, in seconds of the file, while it plays; None otherwise.

        This is the position QtMultimedia reports (``QMediaPlayer.position``, whole
        milliseconds, updated in steps); :class:`app.models.playback.PlaybackClock` follows it.
        """
        if not self._available or self._player.playbackState() != self._playing_state:
            return None
        return self._player.position() / 1000.0

    def stop(self) -> None:
        if self._available:
            self._player.stop()
