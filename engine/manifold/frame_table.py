"""The per-frame results of a fitted manifold as one tidy table, and as Praat tiers per utterance.

:func:`frame_table` gives one row per frame: utterance, speaker, time, frame, the phone
and kinematic landmark at it, the opening measure (the lip aperture, or the first shape
component standing in when the corpus names no lip points), the movement class, the
state, the frame's S and V coordinates and its F^x and F^y coordinates, each column
with its unit and meaning (:class:`FrameTable`). :func:`utterance_tiers` gives an
utterance's Praat tiers: its phones as read, the four movement classes as intervals and
the kinematic landmarks as points (written by :func:`engine.io.writers.praat.write_textgrid`).

Where the tangent frames come in (the class of each frame and its S and V
coordinates) is :func:`tangent_columns` alone.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from engine.io.writers.tidy import NA

__all__ = ["FrameTable", "frame_table", "tangent_columns", "opening_measure", "class_intervals", "utterance_tiers",
           "write_textgrids", "CLASS_LABELS", "NA", "UNKNOWN_SPEAKER", "UNLABELLED"]

#: the ``speaker`` of an utterance the corpus names no speaker for (a word, not a missing value: R's read.csv and
#: readr read a column of missing values as logical, not text)
UNKNOWN_SPEAKER = "unknown"
#: the ``phone`` of every frame of a corpus without phone labels (likewise)
UNLABELLED = "unlabelled"
#: values of the ``class`` column, ``engine.manifold.tangent.CLASS_NAMES`` in snake_case
CLASS_LABELS = ("opening_accelerating", "opening_decelerating", "closing_accelerating", "closing_decelerating")


@dataclass
class FrameTable:
    """Columns of equal length, in order, with their units and meanings.

    Attributes
    ----------
    columns : dict of str to ndarray of shape (n_rows,)
        Numbers as float or int arrays; text as object arrays with None where missing.
    units : dict of str to str
    descriptions : dict of str to str
    notes : list of str
        What a reader of the table should know (which measure stands in for the aperture, ...).
    rate : float
        Frames per second.
    source : str
        The manifold the table comes from.
    """

    columns: dict
    units: dict
    descriptions: dict
    notes: list = field(default_factory=list)
    rate: float = 60.0
    source: str = ""

    @property
    def n_rows(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def metadata(self, table_name: str = "") -> dict:
        """The sidecar description: every column's unit and meaning, the notes."""
        return {"table": table_name, "rows": self.n_rows, "frame_rate_hz": self.rate, "source": self.source,
                "missing_values": NA,
                "columns": {k: {"unit": self.units.get(k, ""), "description": self.descriptions.get(k, "")}
                            for k in self.columns},
                "notes": list(self.notes)}


def opening_measure(manifold):
    """What "opening" is measured by, per frame: ``(values (N,), column name, unit, description)``.

    The lip aperture (:func:`engine.recordings.kinematics.lip_aperture`) when the corpus names upper
    and lower lip points; otherwise the first shape component F^x_1 (oriented so that +
    is opening, as the tangent frames read it).
    """
    from engine.recordings.kinematics import lip_aperture

    ap = lip_aperture(manifold.corpus_)
    if ap is not None:
        return (np.asarray(ap, np.float64), "lip_aperture", manifold.corpus_.unit_label,
                "distance between the upper- and lower-lip point centroids")
    return (np.asarray(manifold.Fx_[:, 0], np.float64), "opening_fx1", "shape-space units (F^x)",
            "first shape component F^x_1 (+ = opening), standing in for the lip aperture: the corpus names "
            "no upper/lower lip points")


def tangent_columns(manifold) -> dict:
    """The tangent frames' reading of every frame: ``{"class": ..., "s": ..., "v": ...}``.

    ``class`` (object array, None in an utterance of one frame, which has no step) from
    ``tangent_.classes_``; ``s`` and ``v`` from
    :meth:`engine.manifold.tangent.TangentFrames.sv_coordinates` (the opening and its velocity
    read on the manifold), the coordinates the figures use. The only place the table
    and the TextGrids read the tangent frames.
    """
    t = manifold.tangent_
    cls = np.asarray(t.classes_)
    lab = np.array([None, *CLASS_LABELS], dtype=object)[np.where(cls >= 0, cls + 1, 0)]
    sv = t.sv_coordinates()
    return {"class": lab, "s": sv[:, 0], "v": sv[:, 1]}


def _phone_at_frames(u, rate) -> np.ndarray:
    """Label of the phone interval holding each frame's time (object array, None outside every phone)."""
    out = np.full(u.n_frames, None, dtype=object)
    if not u.phones:
        return out
    t = np.arange(u.n_frames) / rate
    starts = np.array([p.start for p in u.phones])
    ends = np.array([p.end for p in u.phones])
    k = np.searchsorted(starts, t, side="right") - 1
    ok = (k >= 0) & (t < ends[np.clip(k, 0, None)])
    labels = np.array([p.label for p in u.phones], dtype=object)
    out[ok] = labels[k[ok]]
    return out


def landmarks(manifold, opening) -> tuple[np.ndarray, np.ndarray]:
    """Kinematic landmarks (corpus frames, labels) of the opening measure
    (:func:`engine.recordings.kinematics.kinematic_landmarks`)."""
    from engine.recordings.kinematics import kinematic_landmarks

    return kinematic_landmarks(manifold.corpus_, aperture=opening)


def frame_table(manifold, *, n_fx: int | None = None, source: str = "") -> FrameTable:
    """One row per frame of ``manifold`` (see the module docstring).

    Parameters
    ----------
    manifold : Manifold
        Fitted.
    n_fx : int, optional
        Shape components written (``fx_1 .. fx_k``); default all of them.
    source : str
        Where the manifold came from, for the metadata.

    Returns
    -------
    FrameTable
        Columns ``utterance, speaker, time_s, frame, phone, landmark, <opening>, class,
        state, [s,] v, fx_1..fx_k, fy_1..fy_3``: ``s`` (S) only where it is not the opening
        column itself. Text columns are never missing throughout (R reads such a column as
        logical): an unnamed speaker is :data:`UNKNOWN_SPEAKER`, the phone of a corpus without
        phone labels :data:`UNLABELLED`.
    """
    from engine.recordings.kinematics import LANDMARK_LABELS

    c = manifold.corpus_
    N, rate = c.n_frames, float(c.rate)
    m = manifold.Fx_.shape[1]
    k = m if n_fx is None else int(n_fx)
    if not 0 <= k <= m:
        raise ValueError(f"n_fx={n_fx!r}: the manifold has {m} shape components; give 0 to {m}")
    utt = np.empty(N, dtype=object)
    spk = np.empty(N, dtype=object)
    frame = np.empty(N, dtype=np.int64)
    phone = np.empty(N, dtype=object)
    for u in c.utterances:
        sl = slice(u.start, u.stop)
        utt[sl] = u.id
        spk[sl] = u.speaker or UNKNOWN_SPEAKER
        frame[sl] = np.arange(u.n_frames)
        phone[sl] = _phone_at_frames(u, rate)
    if not any(u.phones for u in c.utterances):
        phone[:] = UNLABELLED
    opening, name, unit, what = opening_measure(manifold)
    lm = np.full(N, None, dtype=object)
    lf, ll = landmarks(manifold, opening)
    lm[lf] = ll
    tan = tangent_columns(manifold)
    # S is the opening measure itself where the tangent frames read the lip aperture: written once, by its name
    s_is_opening = np.allclose(tan["s"], opening, rtol=1e-5, atol=1e-6 * max(float(np.abs(opening).max()), 1.0))
    cols = {"utterance": utt, "speaker": spk, "time_s": frame / rate, "frame": frame, "phone": phone,
            "landmark": lm, name: opening, "class": tan["class"],
            "state": np.asarray(manifold.states_.labels_, np.int64), "s": tan["s"], "v": tan["v"]}
    units = {"utterance": "", "speaker": "", "time_s": "s", "frame": f"frames at {rate:g} Hz", "phone": "",
             "landmark": "", name: unit, "class": "", "state": "index",
             "s": manifold.tangent_.opening_unit_ or "shape-space units (F^x)",
             "v": f"{manifold.tangent_.opening_unit_ or 'shape-space units (F^x)'} per s"}
    desc = {"utterance": "utterance id", "speaker": f"speaker ({UNKNOWN_SPEAKER!r} when the corpus does not say)",
            "time_s": "time of the frame from the start of its utterance",
            "frame": "frame number within the utterance, from 0",
            "phone": f"label of the phone interval holding the frame (missing outside every phone; {UNLABELLED!r} "
                     "throughout when the corpus has no phone labels)",
            "landmark": f"kinematic landmark at this frame, one of {', '.join(LANDMARK_LABELS)} (aperture maximum, "
                        "minimum, peak opening / closing velocity; missing elsewhere)",
            name: what,
            "class": f"movement class of the frame's step (from the previous to the next frame), one of "
                     f"{', '.join(CLASS_LABELS)} (missing in an utterance of one frame)",
            "state": "state of the state graph the frame belongs to",
            "s": f"S: the opening the tangent frames read ({manifold.tangent_.opening_source_ or 'F^x_1'}), "
                 f"where it is not {name} itself",
            "v": f"V: the velocity of the opening S ({'the ' + name + ' column' if s_is_opening else 's'}) read on "
                 "the manifold, the step times the opening's local gradient (> 0: opening)"}
    if s_is_opening:
        del cols["s"], units["s"], desc["s"]
    for j in range(k):
        cols[f"fx_{j + 1}"] = np.asarray(manifold.Fx_[:, j], np.float64)
        units[f"fx_{j + 1}"] = "shape-space units (F^x)"
        desc[f"fx_{j + 1}"] = f"shape coordinate F^x_{j + 1}" + (" (+ = opening)" if j == 0 else "")
    for j in range(min(3, manifold.Fy_.shape[1])):
        cols[f"fy_{j + 1}"] = np.asarray(manifold.Fy_[:, j], np.float64)
        units[f"fy_{j + 1}"] = "embedding units (F^y)"
        desc[f"fy_{j + 1}"] = f"manifold coordinate F^y_{j + 1}"
    notes = [f"{name}: {what}"]
    if s_is_opening:
        notes.append(f"S, the opening the tangent frames read, is {name} itself: one column, {name}; v is its "
                     "velocity")
    src = getattr(manifold.tangent_, "opening_source_", None)
    if src:
        notes.append(f"the movement classes take 'opening' from {src}")
    if not any(u.phones for u in c.utterances):
        notes.append(f"the corpus has no phone labels: the phone column is {UNLABELLED!r} throughout; the landmark "
                     "column marks the kinematic landmarks")
    return FrameTable(columns=cols, units=units, descriptions=desc, notes=notes, rate=rate, source=source)


def class_intervals(labels, rate: float) -> list[tuple[float, float, str]]:
    """Runs of one movement class as intervals ``(start s, end s, label)``.

    ``labels`` (one per frame of an utterance, None where there is no step) gives frame
    i's class for the step from frame i to i + 1, the span ``[i / rate, (i + 1) / rate]``;
    consecutive frames of one class make one interval.
    """
    out = []
    prev, start = None, 0
    for i, lab in enumerate(list(labels) + [None]):
        if lab != prev:
            if prev is not None:
                out.append((start / rate, i / rate, prev))
            prev, start = lab, i
    return out


def utterance_tiers(manifold, table: FrameTable, uid: str):
    """Praat tiers of utterance ``uid``: ``(xmin, xmax, tiers)`` for :func:`engine.io.writers.praat.write_textgrid`.

    Tiers: ``phones`` (the utterance's phones as read), ``class`` (the movement classes
    as intervals, :func:`class_intervals`) and ``landmarks`` (a point tier of the
    kinematic landmarks). Times from the utterance start; ``xmax`` is the recording's duration
    (``Utterance.duration_s``: a resampled recording ends where it did, not at its last frame
    rounded up), else covers its frames and its phones.
    """
    from engine.io.writers.praat import IntervalTier, PointTier

    c = manifold.corpus_
    u = c.utterance(uid)
    rate = float(c.rate)
    sl = slice(u.start, u.stop)
    xmax = float(u.duration_s) or max(u.n_frames / rate, max((p.end for p in u.phones), default=0.0))
    phones = IntervalTier("phones", [(p.start, p.end, p.label) for p in u.phones])
    classes = IntervalTier("class", class_intervals(table.columns["class"][sl], rate))
    lm = table.columns["landmark"][sl]
    points = PointTier("landmarks", [(i / rate, str(lab)) for i, lab in enumerate(lm) if lab is not None])
    return 0.0, xmax, [phones, classes, points]


def write_textgrids(manifold, table: FrameTable, directory, *, names=None, progress=None) -> list:
    """One TextGrid per utterance (:func:`utterance_tiers`) into ``directory`` (created), each atomically.

    ``names``: the file names, default :func:`engine.io.writers.praat.textgrid_names` of the
    utterance ids. Returns the paths written, in utterance order.
    """
    from pathlib import Path

    from engine.io.writers.praat import textgrid_names, write_textgrid
    from engine.progress import report

    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    utts = manifold.corpus_.utterances
    names = list(names) if names is not None else textgrid_names(u.id for u in utts)
    out = []
    for k, (u, name) in enumerate(zip(utts, names)):
        report(progress, "TextGrids", k, len(utts))
        xmin, xmax, tiers = utterance_tiers(manifold, table, u.id)
        out.append(write_textgrid(d / name, xmin, xmax, tiers))
    report(progress, "TextGrids", len(utts), len(utts))
    return out
