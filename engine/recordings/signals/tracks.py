"""Derived signals ("tracks") of a corpus, as articulograph labs compute them.

A track is one number per frame with a name, a unit and a meaning. The positions are
low-passed first (zero phase, :mod:`engine.recordings.signals.filters`; ``lowpass_hz=None``
keeps them raw), then:

========================  ======================================================================
``lip_aperture``          distance between the upper- and lower-lip centroids (mm)
``lip_protrusion``        the lips' centroid (upper and lower lip) along the talker's forward
                          axis (:func:`engine.recordings.orientation.anatomical_frame`), against
                          the reference points' centroid when the corpus has reference points
                          (head sensors), else against the corpus mean (+ = forward)
``speed_<point>``         tangential velocity of a point: the length of its 3-D (2-D)
                          velocity, mm/s
``<point>_forward``       a point's position along the talker's forward axis, against its
                          corpus mean (mm); ``<point>_up`` and ``<point>_left`` along the up and
                          left axes
``rms_<point>``           the point's sensor quality value per frame, when the file had one
                          (:mod:`engine.recordings.signals.quality`; not filtered)
========================  ======================================================================

:func:`available_tracks` lists what a corpus can give; :func:`derived_track` computes one.
Tracks are what ``lipspace table --tracks`` writes, what the gestural landmarks
(:mod:`engine.recordings.signals.gestures`) run on, and what the window draws under its
timeline (through :mod:`app.models.tracks`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine.recordings.signals.filters import DEFAULT_CUTOFF_HZ, lowpass

__all__ = ["Track", "available_tracks", "derived_track", "derived_tracks", "TrackError", "column_name"]

_AXES = ("forward", "up", "left")


class TrackError(ValueError):
    """A track the corpus cannot give; the message names it, why and what it can give."""


@dataclass(frozen=True)
class Track:
    """One derived signal.

    Attributes
    ----------
    name : str
    values : ndarray of shape (n_frames,), float64
    unit : str
    description : str
        What it is, including the filter applied.
    lowpass_hz : float or None
    """

    name: str
    values: np.ndarray
    unit: str
    description: str
    lowpass_hz: float | None = None


def column_name(track_name: str) -> str:
    """The tidy-table column of a track: lower case, other characters as ``_`` (``speed_UL`` -> ``speed_ul``)."""
    import re

    return re.sub(r"[^0-9a-z]+", "_", track_name.lower()).strip("_")


def _names(corpus) -> list[str]:
    return list(corpus.point_names or [f"p{j}" for j in range(corpus.n_points)])


def available_tracks(corpus) -> list[str]:
    """Every track name ``corpus`` can give (module docstring), lips first."""
    out = []
    up, lo = corpus.role_points("upper_lip"), corpus.role_points("lower_lip")
    if up.size and lo.size:
        out.append("lip_aperture")
        if _frame(corpus).source != "none":
            out.append("lip_protrusion")
    names = _names(corpus)
    out += [f"speed_{n}" for n in names]
    if _frame(corpus).source != "none":
        axes = _AXES[:2] if corpus.dims == 2 else _AXES
        out += [f"{n}_{a}" for n in names for a in axes]
    from engine.recordings.signals.quality import sensor_quality

    sq = sensor_quality(corpus)
    if sq is not None:
        out += [f"{sq[0]}_{n}" for n in names]
    return out


def _frame(corpus):
    cached = corpus.__dict__.get("_anatomical_frame")
    if cached is None or cached[0] is not corpus.frames:
        from engine.recordings.orientation import anatomical_frame

        cached = (corpus.frames, anatomical_frame(corpus))
        corpus.__dict__["_anatomical_frame"] = cached
    return cached[1]


def _points(corpus, idx) -> np.ndarray:
    """Points ``idx`` of every frame, (N, len(idx), dims) float64, read window by window."""
    from functools import partial

    from engine.recordings.frame_blocks import map_frames

    d = corpus.dims
    cols = np.concatenate([np.arange(i * d, (i + 1) * d) for i in idx])
    parts = map_frames(partial(_columns, cols=cols), corpus.frames)
    return np.concatenate(parts).reshape(corpus.n_frames, len(idx), d)


def _columns(F, a, b, *, cols):
    return np.asarray(F[:, cols], np.float64)


def _point_index(corpus, name: str) -> int:
    names = _names(corpus)
    upper = {n.upper(): i for i, n in enumerate(names)}
    i = upper.get(name.upper())
    if i is None:
        raise TrackError(f"{corpus.name}: no point {name!r}; its points are {', '.join(names[:12])}")
    return i


def derived_track(corpus, name: str, *, lowpass_hz: float | None = DEFAULT_CUTOFF_HZ, against: str | None = None):
    """Compute track ``name`` of ``corpus`` (module docstring).

    Parameters
    ----------
    corpus : Corpus
    name : str
        One of :func:`available_tracks`.
    lowpass_hz : float or None
        Cut-off of the zero-phase low-pass applied to the positions first; None: raw.
    against : {"reference", "mean"} or None
        ``lip_protrusion`` only: its zero (default: the reference points when there are any).

    Returns
    -------
    Track

    Raises
    ------
    TrackError
        An unknown name, a point the corpus does not have, a track its roles or frame cannot give.
    """
    bounds, rate = corpus.bounds, corpus.rate
    filt = f", positions low-passed at {lowpass_hz:g} Hz (zero phase)" if lowpass_hz else ", unfiltered positions"

    def smooth(x):
        return lowpass(x, bounds, rate, cutoff_hz=lowpass_hz) if lowpass_hz else np.asarray(x, np.float64)

    unit = corpus.unit_label
    if name == "lip_aperture":
        up, lo = corpus.role_points("upper_lip"), corpus.role_points("lower_lip")
        if not (up.size and lo.size):
            raise TrackError(f"{corpus.name}: lip_aperture needs upper_lip and lower_lip points (import with a "
                             "layout or --roles naming them)")
        P = smooth(_points(corpus, np.r_[up, lo]).reshape(corpus.n_frames, -1)).reshape(corpus.n_frames, -1,
                                                                                         corpus.dims)
        v = np.linalg.norm(P[:, :up.size].mean(axis=1) - P[:, up.size:].mean(axis=1), axis=1)
        return Track(name, v, unit, "distance between the upper- and lower-lip centroids" + filt, lowpass_hz)
    if name == "lip_protrusion":
        return _protrusion(corpus, smooth, against, filt, lowpass_hz)
    if name.startswith("speed_"):
        i = _point_index(corpus, name[len("speed_"):])
        from engine.recordings.signals.filters import velocity

        V = velocity(smooth(_points(corpus, [i])[:, 0]), bounds, rate)
        return Track(name, np.linalg.norm(V, axis=1), f"{unit}/s",
                     f"tangential velocity of {_names(corpus)[i]} (length of its velocity)" + filt, lowpass_hz)
    for axis in _AXES:
        if name.endswith("_" + axis):
            i = _point_index(corpus, name[: -len(axis) - 1])
            fr = _frame(corpus)
            if fr.source == "none":
                raise TrackError(f"{corpus.name}: {name}: the talker's axes are not known (import with --axes or "
                                 "roles naming the lips)")
            row = _axis_row(fr, axis, corpus.dims, name)
            x = smooth(_points(corpus, [i])[:, 0] @ row)
            return Track(name, x - x.mean(), unit, f"position of {_names(corpus)[i]} along the talker's {axis} "
                         "axis, against its corpus mean" + filt, lowpass_hz)
    from engine.recordings.signals.quality import sensor_quality

    sq = sensor_quality(corpus)
    if sq is not None and name.startswith(sq[0] + "_"):
        i = _point_index(corpus, name[len(sq[0]) + 1:])
        return Track(name, sq[1][:, i], "", f"{sq[0]} quality value of {_names(corpus)[i]} as recorded (missing "
                     "where not measured)", None)
    raise TrackError(f"{corpus.name}: no track {name!r}; it has {', '.join(available_tracks(corpus)[:10])} ...")


def _axis_row(frame, axis, dims, name):
    rows = {3: {"left": 0, "up": 1, "forward": 2}, 2: {"forward": 0, "up": 1}}[dims]
    if axis not in rows:
        raise TrackError(f"{name}: 2-D data have no left axis")
    return frame.matrix[rows[axis]]


def _protrusion(corpus, smooth, against, filt, lowpass_hz):
    up, lo = corpus.role_points("upper_lip"), corpus.role_points("lower_lip")
    fr = _frame(corpus)
    if not (up.size and lo.size) or fr.source == "none":
        raise TrackError(f"{corpus.name}: lip_protrusion needs upper_lip and lower_lip points and the talker's "
                         "forward axis (roles naming the lips, or import --axes)")
    ref = corpus.role_points("reference")
    against = against or ("reference" if ref.size else "mean")
    if against not in ("reference", "mean"):
        raise TrackError(f"lip_protrusion against {against!r}; expected 'reference' or 'mean'")
    if against == "reference" and not ref.size:
        raise TrackError(f"{corpus.name}: lip_protrusion against the reference: the corpus has no reference points "
                         "(rigid registration removes them; use against='mean')")
    fwd = _axis_row(fr, "forward", corpus.dims, "lip_protrusion")
    lips = smooth(_points(corpus, np.r_[up, lo]).mean(axis=1) @ fwd)
    if against == "reference":
        v = lips - smooth(_points(corpus, ref).mean(axis=1) @ fwd)
        what = "against the reference points' centroid"
    else:
        v = lips - lips.mean()
        what = "against its corpus mean"
    return Track("lip_protrusion", v, corpus.unit_label,
                 f"the lips' centroid along the talker's forward axis, {what} (+ = forward)" + filt, lowpass_hz)


def derived_tracks(corpus, names, **kw) -> list[Track]:
    """:func:`derived_track` of every name, in order."""
    return [derived_track(corpus, n, **kw) for n in names]
