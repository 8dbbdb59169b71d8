"""The derived tracks drawn under the timeline, Qt-free: which channels, their values per utterance, fixed axes.

Like mview's and VisArtico's signal displays, the window shows several channels
(lip aperture, protrusion, a sensor's tangential velocity, its rms ...) stacked under the
timeline. :class:`TrackPanel` holds what they show and computes everything the drawing
needs; a view observes :attr:`TrackPanel.changed` and draws :meth:`TrackPanel.view` of the
current utterance.

* Every track is computed once over the whole corpus
  (:func:`engine.recordings.signals.tracks.derived_track`, positions low-passed at
  :attr:`lowpass_hz`), so moving between utterances costs a slice.
* Each channel's y-range is fixed over the corpus (1st-99th percentile, padded by 5 %),
  so a channel's scale does not jump from one utterance to the next.
* ``changed`` is emitted with the reason: ``"channels"`` (added, removed, reordered) or
  ``"lowpass"`` (every value changed).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.models.state import Event
from engine.recordings.signals.filters import DEFAULT_CUTOFF_HZ, check_cutoff

__all__ = ["TrackPanel", "TrackView", "Channel"]


@dataclass(frozen=True)
class Channel:
    """One channel of one utterance: ``values`` (n,) with NaN where unknown, ``y_range`` fixed over the corpus."""

    name: str
    values: np.ndarray
    unit: str
    description: str
    y_range: tuple


@dataclass(frozen=True)
class TrackView:
    """What the panel shows for one utterance: frame ``times`` (n,) in seconds from its start, and its channels."""

    utterance: str
    times: np.ndarray
    channels: tuple


class TrackPanel:
    """The channels under the timeline (module docstring).

    Parameters
    ----------
    corpus : Corpus
    channels : sequence of str, optional
        Initial channels (default: ``lip_aperture`` when the corpus has one, else none).
    lowpass_hz : float or None
        Cut-off of the zero-phase low-pass applied to positions before tracks are derived.
    """

    def __init__(self, corpus, *, channels=None, lowpass_hz: float | None = DEFAULT_CUTOFF_HZ):
        from engine.recordings.signals.tracks import available_tracks

        self.corpus = corpus
        self.available = tuple(available_tracks(corpus))
        self._lowpass = self._checked(lowpass_hz)
        self._cache: dict = {}
        self.changed = Event("tracks.changed")
        default = ("lip_aperture",) if "lip_aperture" in self.available else ()
        self._channels: list[str] = []
        for name in (default if channels is None else channels):
            self._check(name)
            self._channels.append(name)

    # ------------------------------------------------------------ what is shown
    @property
    def channels(self) -> tuple:
        return tuple(self._channels)

    @property
    def lowpass_hz(self) -> float | None:
        return self._lowpass

    def _checked(self, hz):
        return None if hz is None else check_cutoff(hz, self.corpus.rate)

    def _check(self, name):
        if name not in self.available:
            raise ValueError(f"no track {name!r} in {self.corpus.name}; it has {', '.join(self.available[:10])} ...")

    def add(self, name: str, index: int | None = None) -> None:
        """Show channel ``name`` (at ``index``, default last); nothing if it is shown already."""
        self._check(name)
        if name in self._channels:
            return
        self._channels.insert(len(self._channels) if index is None else int(index), name)
        self.changed.emit("channels")

    def remove(self, name: str) -> None:
        """Stop showing channel ``name`` (ValueError if it is not shown)."""
        if name not in self._channels:
            raise ValueError(f"channel {name!r} is not shown; shown: {', '.join(self._channels) or 'none'}")
        self._channels.remove(name)
        self.changed.emit("channels")

    def move(self, name: str, index: int) -> None:
        """Put shown channel ``name`` at position ``index`` (clamped)."""
        if name not in self._channels:
            raise ValueError(f"channel {name!r} is not shown")
        self._channels.remove(name)
        self._channels.insert(int(np.clip(index, 0, len(self._channels))), name)
        self.changed.emit("channels")

    def set_lowpass(self, hz: float | None) -> None:
        """Change the low-pass cut-off (None: raw positions); every channel is recomputed."""
        hz = self._checked(hz)
        if hz == self._lowpass:
            return
        self._lowpass = hz
        self._cache.clear()
        self.changed.emit("lowpass")

    # ------------------------------------------------------------ values
    def track(self, name: str):
        """The :class:`engine.recordings.signals.tracks.Track` of ``name`` over the corpus, computed once."""
        from engine.recordings.signals.tracks import derived_track

        self._check(name)
        key = (name, self._lowpass)
        if key not in self._cache:
            tr = derived_track(self.corpus, name, lowpass_hz=self._lowpass)
            finite = tr.values[np.isfinite(tr.values)]
            if finite.size:
                lo, hi = np.percentile(finite, [1, 99])
                pad = 0.05 * (hi - lo) if hi > lo else max(abs(hi), 1.0) * 0.05
                rng = (float(lo - pad), float(hi + pad))
            else:
                rng = (0.0, 1.0)
            self._cache[key] = (tr, rng)
        return self._cache[key][0]

    def y_range(self, name: str) -> tuple:
        """The fixed y-range of channel ``name`` over the corpus."""
        self.track(name)
        return self._cache[(name, self._lowpass)][1]

    def view(self, utterance) -> TrackView:
        """The shown channels of ``utterance`` (an id or an Utterance)."""
        u = self.corpus.utterance(getattr(utterance, "id", utterance))
        chans = []
        for name in self._channels:
            tr = self.track(name)
            chans.append(Channel(name, tr.values[u.start:u.stop], tr.unit, tr.description, self.y_range(name)))
        return TrackView(u.id, np.arange(u.n_frames) / self.corpus.rate, tuple(chans))

    def value_at(self, name: str, frame: int) -> float:
        """Channel ``name`` at corpus frame ``frame`` (a readout under the cursor)."""
        return float(self.track(name).values[int(frame)])
