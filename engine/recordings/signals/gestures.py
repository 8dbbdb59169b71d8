"""Gestural landmarks of a track, as mview's ``findgest``, EMU's anagest and R ``ag501::FindLandmarks`` give them.

A **gesture** is a movement of a track (the lip aperture, a sensor's height ...) to a
target and back: for a constriction the track falls to a minimum and rises again (the
aperture closing for /p/ and opening after it); ``target="max"`` takes maxima instead
(protrusion for /u/). Per gesture, on the low-passed track and its velocity v:

=========  =================================================================================
``GONS``   gesture onset: before PVEL, the last time the speed toward the target is
           below ``threshold`` (20 %) of its peak
``PVEL``   peak velocity of the movement toward the target
``NONS``   nucleus onset: after PVEL, the speed toward the target falls below the
           threshold of its peak
``MAXC``   maximum constriction: the track's extremum between NONS and NOFFS (the
           middle of a flat extremum)
``NOFFS``  nucleus offset: before PVEL2, the speed away rises above the threshold of
           its peak
``PVEL2``  peak velocity of the movement away from the target
``GOFFS``  gesture offset: after PVEL2, the speed away falls below the threshold of its peak
=========  =================================================================================

Targets are the track's extrema standing out by ``prominence`` of its robust range
over the corpus (5th-95th percentile), at least ``min_separation_s`` apart; the
peak speed toward a target is searched back to the previous opposite extremum, the
peak speed away forward to the next; onset and offset as far as the neighbouring
targets. Crossing times are interpolated linearly between
frames, peak times by a parabola through the peak frame and its neighbours, so
landmarks are not tied to the frame grid. A landmark that cannot be found (a gesture
cut by the utterance's start or end, a movement with no speed) is missing (NaN).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from engine.recordings.signals.filters import DEFAULT_CUTOFF_HZ, velocity

__all__ = ["LANDMARKS", "GestureSet", "find_gestures", "gestures_of_signal", "remeasure", "landmark_order_ok",
           "DEFAULT_THRESHOLD", "DEFAULT_PROMINENCE", "target_of", "gesture_key_frames", "with_gesture_labels"]

#: landmark names in time order
LANDMARKS = ("GONS", "PVEL", "NONS", "MAXC", "NOFFS", "PVEL2", "GOFFS")
#: share of the peak speed that marks onsets and offsets (the usual 20 %)
DEFAULT_THRESHOLD = 0.2
#: share of the track's robust range a target must stand out by
DEFAULT_PROMINENCE = 0.15
_TARGETS = {"lip_aperture": "min", "lip_protrusion": "max"}


@dataclass(frozen=True)
class GestureSet:
    """The gestures of one track over a corpus.

    Attributes
    ----------
    track : str
    unit : str
        The track's unit (velocities are in ``unit``/s).
    target : {"min", "max"}
    threshold : float
    lowpass_hz : float or None
    rate : float
    utterance_ids : tuple of str
        The corpus's utterances, in order (``utterance`` indexes them).
    utterance : ndarray of shape (G,) int
    times : ndarray of shape (G, 7) float
        Landmark times in :data:`LANDMARKS` order, seconds from the utterance start; NaN missing.
    peak_velocity : ndarray of shape (G, 2) float
        Speed at PVEL (toward the target) and at PVEL2 (away), ``unit``/s, positive.
    maxc_value : ndarray of shape (G,) float
        The track at MAXC.
    """

    track: str
    unit: str
    target: str
    threshold: float
    lowpass_hz: float | None
    rate: float
    utterance_ids: tuple
    utterance: np.ndarray
    times: np.ndarray
    peak_velocity: np.ndarray
    maxc_value: np.ndarray

    def __len__(self) -> int:
        return int(self.utterance.shape[0])

    def of_utterance(self, uid) -> np.ndarray:
        """Indices of the gestures of utterance ``uid`` (an id or a number), in time order."""
        k = uid if isinstance(uid, (int, np.integer)) else self.utterance_ids.index(uid)
        return np.flatnonzero(self.utterance == k)

    def frames(self, bounds) -> np.ndarray:
        """Corpus frame of every landmark, (G, 7) int64, -1 where missing (``bounds``: the corpus's)."""
        b = np.asarray(bounds, np.int64)[self.utterance]
        f = np.rint(np.nan_to_num(self.times, nan=-1.0) * self.rate).astype(np.int64)
        out = np.clip(b[:, :1] + f, b[:, :1], b[:, 1:] - 1)
        return np.where(np.isfinite(self.times), out, -1)

    def with_times(self, times) -> GestureSet:
        """A copy with other landmark times (values not re-measured: :func:`remeasure`)."""
        t = np.asarray(times, np.float64)
        if t.shape != self.times.shape:
            raise ValueError(f"times of shape {t.shape}; expected {self.times.shape}")
        return replace(self, times=t)

    def subset(self, index) -> GestureSet:
        idx = np.asarray(index)
        return replace(self, utterance=self.utterance[idx], times=self.times[idx],
                       peak_velocity=self.peak_velocity[idx], maxc_value=self.maxc_value[idx])


def target_of(track: str, target: str = "auto") -> str:
    """``"min"`` / ``"max"``: the target kind of ``track`` (``auto``: minima of the aperture, maxima of the
    protrusion); ValueError for ``auto`` on another track."""
    if target in ("min", "max"):
        return target
    if target != "auto":
        raise ValueError(f"target {target!r}; expected 'min', 'max' or 'auto'")
    if track in _TARGETS:
        return _TARGETS[track]
    raise ValueError(f"track {track!r}: say whether its gestures move to a minimum or a maximum (target='min' or "
                     "'max'; lipspace table --gesture-target)")


def landmark_order_ok(times) -> np.ndarray:
    """Per gesture, whether its present landmarks are in :data:`LANDMARKS` order (non-decreasing)."""
    t = np.asarray(times, np.float64)
    ok = np.ones(len(t), bool)
    for i in range(len(t)):
        r = t[i][np.isfinite(t[i])]
        ok[i] = bool(np.all(np.diff(r) >= -1e-12))
    return ok


def find_gestures(corpus, track: str = "lip_aperture", *, target: str = "auto",
                  threshold: float = DEFAULT_THRESHOLD, prominence: float = DEFAULT_PROMINENCE,
                  min_separation_s: float = 0.06, lowpass_hz: float | None = DEFAULT_CUTOFF_HZ) -> GestureSet:
    """The gestures of ``track`` over every utterance of ``corpus`` (module docstring).

    Parameters
    ----------
    corpus : Corpus
    track : str
        A name of :func:`engine.recordings.signals.tracks.available_tracks`.
    target : {"auto", "min", "max"}
    threshold : float
        Share of each peak speed marking onsets and offsets, in (0, 1).
    prominence : float
        Share of the track's robust range a target must stand out by, in (0, 1).
    min_separation_s : float
    lowpass_hz : float or None
        Cut-off of the zero-phase low-pass applied to the positions first.

    Returns
    -------
    GestureSet
    """
    from engine.recordings.signals.tracks import derived_track

    tr = derived_track(corpus, track, lowpass_hz=lowpass_hz)
    gs = gestures_of_signal(tr.values, corpus.bounds, corpus.rate, target=target_of(track, target),
                            threshold=threshold, prominence=prominence, min_separation_s=min_separation_s)
    return replace(gs, track=track, unit=tr.unit, lowpass_hz=lowpass_hz,
                   utterance_ids=tuple(u.id for u in corpus.utterances))


def gestures_of_signal(x, bounds, rate: float, *, target: str = "min", threshold: float = DEFAULT_THRESHOLD,
                       prominence: float = DEFAULT_PROMINENCE, min_separation_s: float = 0.06) -> GestureSet:
    """The gestures of a signal ``x`` (N,) over utterances ``bounds`` (U, 2) at ``rate`` (no filtering here).

    The track name and unit of the result are empty; :func:`find_gestures` fills them.
    """
    from scipy.signal import find_peaks

    if not 0 < float(threshold) < 1:
        raise ValueError(f"threshold {threshold!r}; expected a share of the peak speed in (0, 1), e.g. 0.2")
    if not 0 < float(prominence) < 1:
        raise ValueError(f"prominence {prominence!r}; expected a share of the track's range in (0, 1)")
    if target not in ("min", "max"):
        raise ValueError(f"target {target!r}; expected 'min' or 'max'")
    x = np.asarray(x, np.float64)
    bounds = np.asarray(bounds, np.int64)
    sign = 1.0 if target == "max" else -1.0
    y = sign * x  # targets are maxima of y; toward the target y rises
    v = velocity(y, bounds, rate)
    finite = y[np.isfinite(y)]
    lo, hi = np.percentile(finite, [5, 95]) if finite.size else (0.0, 0.0)
    prom = prominence * (hi - lo) if hi > lo else None
    dist = max(1, int(round(min_separation_s * rate)))
    utt, times, pv, mv = [], [], [], []
    for k, (a, b) in enumerate(bounds.tolist()):
        seg, vel = y[a:b], v[a:b]
        if b - a < 5 or prom is None:
            continue
        peaks, _ = find_peaks(seg, prominence=prom, distance=dist)
        if not peaks.size:
            continue
        troughs, _ = find_peaks(-seg, prominence=prom, distance=dist)
        plist = peaks.tolist()
        for i, p in enumerate(plist):
            before = troughs[troughs < p]
            after = troughs[troughs > p]
            w0 = int(before[-1]) if before.size else 0
            w1 = int(after[0]) if after.size else b - a - 1
            lim = (plist[i - 1] + 1 if i else 0, plist[i + 1] - 1 if i + 1 < len(plist) else b - a - 1)
            row, speeds = _landmarks(seg, vel, p, w0, w1, threshold, lim)
            utt.append(k)
            times.append(row / rate)
            pv.append(speeds)
            mv.append(sign * _value_at(seg, row[3]))
    G = len(utt)
    return GestureSet(track="", unit="", target=target, threshold=float(threshold), lowpass_hz=None,
                      rate=float(rate), utterance_ids=tuple(str(i) for i in range(len(bounds))),
                      utterance=np.array(utt, np.int64), times=np.array(times, np.float64).reshape(G, 7),
                      peak_velocity=np.array(pv, np.float64).reshape(G, 2), maxc_value=np.array(mv, np.float64))


def _landmarks(y, v, p, w0, w1, theta, lim):
    """Landmark positions (fractional frames within the utterance, NaN missing) of the gesture whose target is
    frame ``p`` of ``y`` (a maximum), its peak speeds searched in ``[w0, w1]`` (between the opposite extrema),
    its onset and offset up to the neighbouring targets ``lim`` (the speed's sign changes at the extremum
    between, possibly between two frames); and the two peak speeds."""
    nan = np.nan
    out = np.full(7, nan)
    toward, away = v[w0:p + 1], -v[p:w1 + 1]  # speed toward the target (y rising), away from it (falling)
    speeds = np.array([nan, nan])
    i1 = w0 + int(np.argmax(toward)) if toward.size else None
    i2 = p + int(np.argmax(away)) if away.size else None
    if i1 is not None and v[i1] > 0:
        out[1], speeds[0] = _parabola(v, i1)
        th = theta * v[i1]
        out[0] = _crossing(v, i1, lim[0] - 1, th)  # backward from PVEL
        out[2] = _crossing(v, i1, p + 1 if i2 is None else i2 + 1, th)  # forward toward the target
    if i2 is not None and -v[i2] > 0:
        t2, s2 = _parabola(-v, i2)
        out[5], speeds[1] = t2, s2
        th = theta * (-v[i2])
        out[4] = _crossing(-v, i2, (w0 if i1 is None else i1) - 1, th)  # backward from PVEL2
        out[6] = _crossing(-v, i2, lim[1] + 1, th)
    lo = out[2] if np.isfinite(out[2]) else p
    hi = out[4] if np.isfinite(out[4]) else p
    out[3] = _extremum(y, min(lo, p), max(hi, p))
    return out, speeds


def _crossing(s, start, stop, th):
    """First fractional frame from ``start`` stepping toward ``stop`` (exclusive) where ``s`` falls below ``th``,
    interpolated between the two frames around it; NaN if it never does."""
    step = 1 if stop > start else -1
    prev = start
    for i in range(start + step, stop, step):
        if not 0 <= i < len(s):
            break
        if s[i] < th:
            d = s[prev] - s[i]
            f = (s[prev] - th) / d if d > 0 else 0.0
            return prev + step * f
        prev = i
    return np.nan


def _parabola(s, i):
    """(fractional frame, value) of the peak of ``s`` at frame ``i`` by a parabola through its neighbours."""
    if 0 < i < len(s) - 1:
        a, b, c = s[i - 1], s[i], s[i + 1]
        den = a - 2 * b + c
        if den < 0:
            d = 0.5 * (a - c) / den
            return i + d, b - 0.25 * (a - c) * d
    return float(i), float(s[i])


def _extremum(y, lo, hi):
    """Fractional frame of the maximum of ``y`` within ``[lo, hi]``: the middle of the frames at the maximum
    (a flat target), else a parabola's vertex."""
    a, b = int(np.ceil(lo - 1e-9)), int(np.floor(hi + 1e-9))
    a, b = max(a, 0), min(max(b, a), len(y) - 1)
    seg = y[a:b + 1]
    top = seg.max()
    tol = 1e-9 * max(1.0, float(np.ptp(y)))
    at = np.flatnonzero(seg >= top - tol)
    if at.size > 1:
        return a + 0.5 * (at[0] + at[-1])
    return _parabola(y, a + int(at[0]))[0]


def _value_at(y, t):
    """``y`` at fractional frame ``t`` (linear between frames); NaN for NaN."""
    if not np.isfinite(t):
        return np.nan
    return float(np.interp(t, np.arange(len(y)), y))


def remeasure(gs: GestureSet, x, bounds) -> GestureSet:
    """The peak speeds and MAXC values of ``gs`` read again from the track ``x`` (N,) at its landmark times (after
    landmarks were moved): speed at PVEL / PVEL2, the track at MAXC. ``x`` is the (low-passed) track the
    gestures were found on."""
    sign = 1.0 if gs.target == "max" else -1.0
    bounds = np.asarray(bounds, np.int64)
    v = velocity(sign * np.asarray(x, np.float64), bounds, gs.rate)
    pv, mv = gs.peak_velocity.copy(), gs.maxc_value.copy()
    for g in range(len(gs)):
        a, b = bounds[gs.utterance[g]]
        f = gs.times[g] * gs.rate
        pv[g, 0] = _value_at(v[a:b], f[1])
        pv[g, 1] = -_value_at(v[a:b], f[5])
        mv[g] = _value_at(np.asarray(x, np.float64)[a:b], f[3])
    return replace(gs, peak_velocity=pv, maxc_value=mv)


def gesture_key_frames(gs: GestureSet, utterance, bounds, *, landmarks=("MAXC",)) -> np.ndarray:
    """Frames (0-based within the utterance, strictly increasing) of the chosen landmarks of every gesture of
    ``utterance``: key frames for synthesis (:func:`engine.phonetics.targets.targets_from_utterance`)."""
    cols = _columns(landmarks)
    k = gs.of_utterance(utterance)
    if not k.size:
        return np.zeros(0, np.int64)
    start = np.asarray(bounds, np.int64)[gs.utterance[k[0]], 0]
    f = gs.frames(bounds)[k][:, cols].ravel()
    return np.unique(f[f >= 0] - start)


def with_gesture_labels(corpus, gs: GestureSet, *, landmarks=LANDMARKS):
    """``corpus`` with its phones replaced by intervals centred on the chosen landmarks, labelled with their names
    (:func:`engine.recordings.kinematics.with_landmark_labels`): clusters, targets and evaluation then use
    them. Where two landmarks fall on one frame the earlier in :data:`LANDMARKS` order is kept."""
    from engine.recordings.kinematics import with_landmark_labels

    cols = _columns(landmarks)
    f = gs.frames(corpus.bounds)[:, cols]
    names = np.array(LANDMARKS)[cols]
    seen: dict[int, str] = {}
    for row in f:
        for fr, lab in zip(row.tolist(), names.tolist()):
            if fr >= 0:
                seen.setdefault(fr, lab)
    frames = np.array(sorted(seen), np.int64)
    return with_landmark_labels(corpus, frames, [seen[i] for i in frames.tolist()],
                                note=f"phones replaced by {len(frames)} gestural landmarks ({', '.join(names)}) of "
                                     f"{gs.track or 'a track'}")


def _columns(landmarks) -> list[int]:
    names = [landmarks] if isinstance(landmarks, str) else list(landmarks)
    bad = [n for n in names if n.upper() not in LANDMARKS]
    if bad or not names:
        raise ValueError(f"landmark(s) {bad or names}; expected some of {', '.join(LANDMARKS)}")
    return [LANDMARKS.index(n.upper()) for n in names]
