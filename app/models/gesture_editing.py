"""Adjusting gestural landmarks by hand, with undo and redo (Qt-free).

Automatic landmarks (:func:`engine.recordings.signals.gestures.find_gestures`) are a start;
a phonetician checks them and moves the ones that are wrong, as in mview. A
:class:`GestureEditor` holds the gestures of one track and every edit:

* :meth:`GestureEditor.move` puts one landmark of one gesture at a new time, clamped
  between its gesture's neighbouring landmarks (their order GONS <= PVEL <= NONS <= MAXC
  <= NOFFS <= PVEL2 <= GOFFS always holds) and inside the utterance; the peak speeds and
  the value at MAXC are read again from the track at the new times;
* :meth:`GestureEditor.clear` marks a landmark as missing, :meth:`GestureEditor.remove`
  takes a whole gesture out (a false detection);
* :meth:`GestureEditor.undo` / :meth:`GestureEditor.redo` step through the edits (a new
  edit after an undo drops the redo steps);
* :meth:`GestureEditor.points` is what a tier under the timeline draws, and
  :meth:`GestureEditor.nearest` what a click or a drag picks; :meth:`GestureEditor.frames`
  gives corpus frames for marks on the manifold view.

``changed`` is emitted after every edit, undo and redo with ``(kind, gesture)``
(``kind``: ``"move"``, ``"clear"``, ``"remove"``, ``"undo"``, ``"redo"``; ``gesture``: the
index it concerns in the current set, or None).
"""
from __future__ import annotations

import numpy as np

from app.models.state import Event
from engine.recordings.signals.gestures import LANDMARKS, remeasure

__all__ = ["GestureEditor", "LANDMARKS"]


def _index(landmark) -> int:
    if isinstance(landmark, (int, np.integer)):
        if not 0 <= int(landmark) < len(LANDMARKS):
            raise IndexError(f"landmark {landmark} out of range 0..{len(LANDMARKS) - 1}")
        return int(landmark)
    name = str(landmark).upper()
    if name not in LANDMARKS:
        raise ValueError(f"landmark {landmark!r}; expected one of {', '.join(LANDMARKS)}")
    return LANDMARKS.index(name)


class GestureEditor:
    """The gestures of one track and their edits (module docstring).

    Parameters
    ----------
    corpus : Corpus
        The corpus the gestures were found on (its utterances and rate).
    gestures : GestureSet
    track : ndarray of shape (n_frames,), optional
        The (low-passed) track the gestures were found on, to re-measure peak speeds and
        the MAXC value after a move; default: computed as
        :func:`engine.recordings.signals.gestures.find_gestures` did.
    """

    def __init__(self, corpus, gestures, *, track=None):
        self.corpus = corpus
        self._gs = gestures
        if track is None and gestures.track:
            from engine.recordings.signals.tracks import derived_track

            track = derived_track(corpus, gestures.track, lowpass_hz=gestures.lowpass_hz).values
        self._track = None if track is None else np.asarray(track, np.float64)
        self._undo: list = []
        self._redo: list = []
        self.changed = Event("gestures.changed")

    @property
    def gestures(self):
        """The current :class:`engine.recordings.signals.gestures.GestureSet`."""
        return self._gs

    @property
    def can_undo(self) -> bool:
        return bool(self._undo)

    @property
    def can_redo(self) -> bool:
        return bool(self._redo)

    # ------------------------------------------------------------ reading
    def _utterance(self, g):
        return self.corpus.utterances[int(self._gs.utterance[g])]

    def bounds(self, gesture: int, landmark) -> tuple[float, float]:
        """``(lo, hi)`` seconds from the utterance start that ``landmark`` of ``gesture`` may move to: between the
        gesture's nearest present landmarks before and after it, and inside the utterance."""
        j = _index(landmark)
        t = self._gs.times[int(gesture)]
        u = self._utterance(int(gesture))
        before = t[:j][np.isfinite(t[:j])]
        after = t[j + 1:][np.isfinite(t[j + 1:])]
        lo = float(before.max()) if before.size else 0.0
        hi = float(after.min()) if after.size else (u.n_frames - 1) / self.corpus.rate
        return lo, hi

    def points(self, utterance) -> list[tuple]:
        """``[(time s, landmark name, gesture, landmark index), ...]`` of ``utterance``'s gestures, by time: what the
        landmark tier draws."""
        out = []
        for g in self._gs.of_utterance(getattr(utterance, "id", utterance)).tolist():
            for j, t in enumerate(self._gs.times[g]):
                if np.isfinite(t):
                    out.append((float(t), LANDMARKS[j], g, j))
        return sorted(out, key=lambda p: (p[0], p[3]))

    def nearest(self, utterance, time_s: float, *, tolerance_s: float = 0.02, landmarks=None):
        """``(gesture, landmark index)`` of the landmark of ``utterance`` nearest ``time_s`` within ``tolerance_s``
        (only those named in ``landmarks``, if given); None when there is none."""
        allowed = None if landmarks is None else {_index(x) for x in landmarks}
        best, dist = None, float(tolerance_s)
        for t, _, g, j in self.points(utterance):
            if allowed is not None and j not in allowed:
                continue
            d = abs(t - float(time_s))
            if d <= dist:
                best, dist = (g, j), d
        return best

    def frames(self, utterance=None) -> np.ndarray:
        """Corpus frames of the landmarks (G, 7), -1 where missing; of one utterance's gestures if given."""
        f = self._gs.frames(self.corpus.bounds)
        if utterance is None:
            return f
        return f[self._gs.of_utterance(getattr(utterance, "id", utterance))]

    # ------------------------------------------------------------ editing
    def _commit(self, new, kind, gesture):
        self._undo.append(self._gs)
        self._redo.clear()
        self._gs = new
        self.changed.emit(kind, gesture)

    def _remeasured(self, gs):
        return remeasure(gs, self._track, self.corpus.bounds) if self._track is not None else gs

    def move(self, gesture: int, landmark, time_s: float) -> float:
        """Move ``landmark`` of ``gesture`` to ``time_s`` (clamped to :meth:`bounds`); returns the time it got."""
        g, j = int(gesture), _index(landmark)
        if not 0 <= g < len(self._gs):
            raise IndexError(f"gesture {g} out of range 0..{len(self._gs) - 1}")
        if not np.isfinite(time_s):
            raise ValueError(f"time {time_s!r}; expected seconds from the utterance start")
        lo, hi = self.bounds(g, j)
        t = float(np.clip(float(time_s), lo, hi))
        if t == self._gs.times[g, j]:
            return t
        times = self._gs.times.copy()
        times[g, j] = t
        self._commit(self._remeasured(self._gs.with_times(times)), "move", g)
        return t

    def clear(self, gesture: int, landmark) -> None:
        """Mark ``landmark`` of ``gesture`` as missing (NaN in the tables, no point on the tier)."""
        g, j = int(gesture), _index(landmark)
        if not np.isfinite(self._gs.times[g, j]):
            return
        times = self._gs.times.copy()
        times[g, j] = np.nan
        self._commit(self._remeasured(self._gs.with_times(times)), "clear", g)

    def remove(self, gesture: int) -> None:
        """Take ``gesture`` out (the following gestures' indices shift down by one)."""
        g = int(gesture)
        if not 0 <= g < len(self._gs):
            raise IndexError(f"gesture {g} out of range 0..{len(self._gs) - 1}")
        keep = np.ones(len(self._gs), bool)
        keep[g] = False
        self._commit(self._gs.subset(np.flatnonzero(keep)), "remove", g)

    def undo(self) -> bool:
        """Undo the last edit; False when there is none."""
        if not self._undo:
            return False
        self._redo.append(self._gs)
        self._gs = self._undo.pop()
        self.changed.emit("undo", None)
        return True

    def redo(self) -> bool:
        """Redo the last undone edit; False when there is none."""
        if not self._redo:
            return False
        self._undo.append(self._gs)
        self._gs = self._redo.pop()
        self.changed.emit("redo", None)
        return True
