"""The signals under the editor's timeline for one corpus: the channels shown, and the gestures of one track (Qt-free).

:class:`Signals` holds a :class:`app.models.tracks.TrackPanel` (the channels the user chose
and the low-pass cut-off) and the gestural landmarks of one track, found over the corpus by
:func:`engine.recordings.signals.gestures.find_gestures` and edited through a
:class:`app.models.gesture_editing.GestureEditor`. What a session keeps of them is
:meth:`Signals.settings`: the channels, the cut-off, the gesture track and threshold, and,
once a landmark was moved or a gesture removed, the landmark times as edited (restored by
:meth:`Signals.gestures_from_settings`, the peak speeds and MAXC values measured again).

Landmarks are drawn in the session palette's colours of kind ``"landmark"``, by the words of
:data:`LANDMARK_WORDS` (the order a gesture takes them).
"""
from __future__ import annotations

import math

import numpy as np

from app.models.tracks import TrackPanel
from engine.recordings.signals.filters import DEFAULT_CUTOFF_HZ
from engine.recordings.signals.gestures import DEFAULT_THRESHOLD, LANDMARKS

__all__ = ["Signals", "LANDMARK_WORDS", "GESTURE_TRACKS", "landmark_colour", "SignalsError", "default_lowpass"]

#: the palette's name of each landmark (app.models.palette.LANDMARK_ORDER)
LANDMARK_WORDS = dict(zip(LANDMARKS, ("gesture onset", "peak velocity (to target)", "nucleus onset",
                                      "maximum constriction", "nucleus offset", "peak velocity (away)",
                                      "gesture offset")))
#: tracks whose gestures have a known target (a minimum of the aperture, a maximum of the protrusion)
GESTURE_TRACKS = ("lip_aperture", "lip_protrusion")


def default_lowpass(rate: float) -> float | None:
    """The window's first cut-off for frames at ``rate`` Hz: :data:`DEFAULT_CUTOFF_HZ` where it lies below the
    Nyquist frequency, else None (raw positions: a 30 Hz video's tracks, which no cut-off below 15 Hz would leave
    the speech movements of)."""
    return DEFAULT_CUTOFF_HZ if DEFAULT_CUTOFF_HZ < 0.5 * float(rate) else None


class SignalsError(ValueError):
    """A session's signals settings that do not fit the corpus (names the field and the value)."""


def landmark_colour(palette, landmark: str):
    """The palette colour of landmark code ``landmark`` (GONS ... GOFFS)."""
    return palette.colour("landmark", LANDMARK_WORDS[str(landmark).upper()])


class Signals:
    """The channels and the gestures of one corpus (module docstring).

    Parameters
    ----------
    corpus : Corpus
    channels : sequence of str, optional
        Channels shown (default: the lip aperture where the corpus has one).
    lowpass_hz : float or None or "default"
        Cut-off of the zero-phase low-pass of the positions (None: raw; "default":
        :func:`default_lowpass` of the corpus's rate).
    gesture_track : str or None or "auto"
        The track whose gestures the tier shows ("auto": the lip aperture where there is one).
    threshold : float
        Share of each peak speed marking onsets and offsets.
    """

    def __init__(self, corpus, *, channels=None, lowpass_hz="default", gesture_track="auto",
                 threshold: float = DEFAULT_THRESHOLD):
        self.corpus = corpus
        if lowpass_hz == "default":
            lowpass_hz = default_lowpass(corpus.rate)
        self.panel = TrackPanel(corpus, channels=channels, lowpass_hz=lowpass_hz)
        if gesture_track == "auto":
            gesture_track = next((t for t in GESTURE_TRACKS if t in self.panel.available), None)
        if gesture_track is not None and gesture_track not in self.gesture_choices():
            raise SignalsError(f"gesture track {gesture_track!r}: {corpus.name} gives gestures of "
                               f"{', '.join(self.gesture_choices()) or 'no track (it has no lip roles)'}")
        if not 0 < float(threshold) < 1:
            raise SignalsError(f"gesture threshold {threshold!r}: a share of the peak speed, above 0 and below 1")
        self.gesture_track = gesture_track
        self.threshold = float(threshold)
        self.editor = None  # a GestureEditor once gestures are found (use)
        self._kept_edits = False  # the landmarks came edited from a session

    # ------------------------------------------------------------ gestures
    def gesture_choices(self) -> list[str]:
        """The tracks whose gestures can be found on this corpus."""
        return [t for t in GESTURE_TRACKS if t in self.panel.available]

    def find(self, progress=None):
        """The gestures of :attr:`gesture_track` over the corpus, at the panel's cut-off (any thread)."""
        from engine.progress import report
        from engine.recordings.signals.gestures import find_gestures

        if self.gesture_track is None:
            return None
        report(progress, "finding gestures", 0, 1)
        gs = find_gestures(self.corpus, self.gesture_track, threshold=self.threshold,
                           lowpass_hz=self.panel.lowpass_hz)
        report(progress, "finding gestures", 1, 1)
        return gs

    def use(self, gestures) -> None:
        """Edit ``gestures`` from now on (a new :class:`GestureEditor`, its history empty; None: no gestures)."""
        from app.models.gesture_editing import GestureEditor

        self._kept_edits = False
        if gestures is None:
            self.editor = None
            return
        track = None
        if gestures.lowpass_hz == self.panel.lowpass_hz and gestures.track in self.panel.available:
            track = self.panel.track(gestures.track).values  # computed once already for the channel
        self.editor = GestureEditor(self.corpus, gestures, track=track)

    @property
    def gestures(self):
        return None if self.editor is None else self.editor.gestures

    @property
    def edited(self) -> bool:
        """Whether the landmarks differ from those found (a move, a landmark cleared, a gesture removed)."""
        return self.editor is not None and (self.editor.can_undo or self._kept_edits)

    # ------------------------------------------------------------ sessions
    def settings(self) -> dict:
        """What a session keeps: channels, cut-off, gesture track and threshold, the edited landmarks."""
        d = {"channels": list(self.panel.channels), "lowpass_hz": self.panel.lowpass_hz,
             "gesture_track": self.gesture_track, "threshold": self.threshold, "gestures": None}
        gs = self.gestures
        if gs is not None and self.edited:
            d["gestures"] = {"lowpass_hz": gs.lowpass_hz,
                             "utterance": [gs.utterance_ids[int(k)] for k in gs.utterance],
                             "times": [[None if not math.isfinite(t) else round(float(t), 6) for t in row]
                                       for row in gs.times]}
        return d

    @classmethod
    def from_settings(cls, corpus, d: dict) -> Signals:
        """The signals a session's :meth:`settings` describe (edited landmarks: :meth:`gestures_from_settings`)."""
        have = TrackPanel(corpus, channels=(), lowpass_hz=None).available
        chans = [c for c in d.get("channels", []) if c in have]  # a channel the corpus lacks: left out, not fatal
        track = d.get("gesture_track", "auto")
        if track is not None and track not in [t for t in GESTURE_TRACKS if t in have]:
            track = "auto"
        try:
            return cls(corpus, channels=chans, lowpass_hz=d.get("lowpass_hz", "default"),
                       gesture_track=track, threshold=d.get("threshold", DEFAULT_THRESHOLD))
        except ValueError as exc:
            raise SignalsError(f"signals settings: {exc}") from None

    def gestures_from_settings(self, d: dict):
        """The edited landmarks a session kept (None when it kept none), their speeds measured again."""
        from engine.recordings.signals.gestures import GestureSet, remeasure, target_of
        from engine.recordings.signals.tracks import derived_track

        rec = d.get("gestures")
        if not rec or self.gesture_track is None:
            return None
        ids = [u.id for u in self.corpus.utterances]
        index = {u: k for k, u in enumerate(ids)}
        missing = sorted({u for u in rec["utterance"] if u not in index})
        if missing:
            raise SignalsError(f"edited gestures name utterance(s) {', '.join(missing[:5])} this corpus lacks")
        times = np.asarray([[np.nan if t is None else float(t) for t in row] for row in rec["times"]], np.float64)
        if times.shape != (len(rec["utterance"]), len(LANDMARKS)):
            raise SignalsError(f"edited gestures: times of shape {times.shape}; expected "
                               f"({len(rec['utterance'])}, {len(LANDMARKS)})")
        utt = np.asarray([index[u] for u in rec["utterance"]], np.int64)
        hz = rec.get("lowpass_hz", self.panel.lowpass_hz)
        tr = derived_track(self.corpus, self.gesture_track, lowpass_hz=hz)
        G = len(utt)
        gs = GestureSet(self.gesture_track, tr.unit, target_of(self.gesture_track), self.threshold, hz,
                        float(self.corpus.rate), tuple(ids), utt, times, np.zeros((G, 2)), np.zeros(G))
        return remeasure(gs, tr.values, self.corpus.bounds)

    def restore(self, d: dict) -> None:
        """Edit the landmarks a session kept, as the start of a new history (their edits are not undone)."""
        gs = self.gestures_from_settings(d)
        if gs is not None:
            self.use(gs)
            self._kept_edits = True
