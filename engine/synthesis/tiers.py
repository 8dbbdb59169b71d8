"""A synthesised trajectory for Praat: its opening per frame and its targets, on the input alignment's timeline.

Targets made from a TextGrid start at its first phone (:func:`engine.phonetics.targets.targets_from_textgrid`
shifts the phones to 0); :func:`synthesis_outputs` puts the synthesised frames back on the
input's clock, so the TextGrid it describes has the input's ``xmin`` and ``xmax`` and its
phone tier as read, and the CSV's ``time_s`` are times of the input. The opening is
measured as in the per-frame table (:func:`engine.manifold.frame_table.opening_measure`): the lip
aperture of the synthesised frames when the corpus names lip points, else F^x_1.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["Timeline", "input_timeline", "synthesis_outputs"]


@dataclass(frozen=True)
class Timeline:
    """An alignment's span and phone tier: ``xmin``, ``xmax`` (s), the tier's name and its phones."""

    xmin: float
    xmax: float
    tier: str
    phones: tuple


def input_timeline(path, *, tier: str | None = None) -> Timeline:
    """The span and phone tier of an alignment file (a TextGrid's own xmin / xmax; a .lab: 0 to its last end)."""
    from engine.files.bounded import input_limit, read_bounded
    from engine.io import read_alignment
    from engine.io.readers.alignment import _parse_textgrid, _pick_tier

    phones = tuple(read_alignment(path, tier=tier))  # a regular file of bounded size, or refused
    data = read_bounded(path, limit=input_limit()[0])[:64].lstrip(b"\xef\xbb\xbf").replace(b"\x00", b"")
    if data.startswith(b"ooBinaryFile") or b"ooTextFile" in data or Path(path).suffix.lower() == ".textgrid":
        grid = _parse_textgrid(path)
        return Timeline(float(grid.xmin), float(grid.xmax), _pick_tier(grid, path, tier), phones)
    return Timeline(0.0, max((p.end for p in phones), default=0.0), "phones", phones)


def _opening(manifold, traj):
    """(values (n,), column name, unit, description) of the synthesised frames' opening."""
    from engine.manifold.frame_table import opening_measure
    from engine.recordings.corpus import Corpus, Utterance
    from engine.recordings.kinematics import lip_aperture

    c = manifold.corpus_
    _, name, unit, what = opening_measure(manifold)
    if name == "lip_aperture":
        frames = np.asarray(traj.frames(manifold), np.float32)
        one = Corpus(frames=frames, rate=c.rate, utterances=[Utterance("synthesis", 0, len(frames))], dims=c.dims,
                     point_names=c.point_names, point_roles=c.point_roles, name="synthesis")
        return np.asarray(lip_aperture(one), np.float64), name, unit, what + " of the synthesised frames", one
    one = Corpus(frames=np.zeros((traj.n_frames, c.dims), np.float32), rate=c.rate,
                 utterances=[Utterance("synthesis", 0, traj.n_frames)], dims=c.dims, name="synthesis")
    return np.asarray(traj.Fx[:, 0], np.float64), name, unit, what, one


def synthesis_outputs(manifold, targets, traj, *, timeline: Timeline | None = None):
    """The CSV table and the TextGrid tiers of a synthesis.

    Parameters
    ----------
    manifold : Manifold
    targets : engine.phonetics.targets.TargetSequence
        What was synthesised.
    traj : engine.synthesis.trajectory.Trajectory
    timeline : Timeline, optional
        The input alignment (:func:`input_timeline`); without it the span is 0 to the
        trajectory's end and the phones are the targets'.

    Returns
    -------
    table : engine.manifold.frame_table.FrameTable
        One row per synthesised frame: ``time_s, frame, phone, target, <opening>[, state]``.
    grid : tuple (xmin, xmax, tiers)
        For :func:`engine.io.writers.praat.write_textgrid`: the phone tier, ``targets`` (points at
        the target frames, labelled with their phones) and ``landmarks`` (the kinematic
        landmarks of the synthesised opening).
    """
    from engine.io.writers.praat import IntervalTier, PointTier
    from engine.manifold.frame_table import FrameTable
    from engine.recordings.kinematics import kinematic_landmarks

    rate = float(targets.rate)
    n = traj.n_frames
    if timeline is None:
        timeline = Timeline(0.0, max(n / rate, max((p.end for p in targets.phones), default=0.0)), "phones",
                            tuple(targets.phones))
        offset = 0.0
    else:  # targets_from_textgrid starts the targets at the first phone: put them back on the input's clock
        offset = (timeline.phones[0].start - targets.phones[0].start) if timeline.phones and targets.phones else 0.0
    t = offset + np.arange(n) / rate
    phone = np.full(n, None, dtype=object)
    for p in timeline.phones:
        phone[(t >= p.start) & (t < p.end)] = p.label
    target = np.full(n, None, dtype=object)
    tf = np.asarray(traj.target_frames, np.int64)
    labels = list(traj.target_labels) or [tg.label for tg in targets.targets]
    ok = (tf >= 0) & (tf < n)
    target[tf[ok]] = np.array([labels[i] if i < len(labels) else "" for i in np.flatnonzero(ok)], dtype=object)
    opening, name, unit, what, one = _opening(manifold, traj)
    cols = {"time_s": t, "frame": np.arange(n), "phone": phone, "target": target, name: opening}
    units = {"time_s": "s", "frame": f"frames at {rate:g} Hz", "phone": "", "target": "", name: unit}
    desc = {"time_s": "time on the input alignment's clock", "frame": "synthesised frame, from 0",
            "phone": f"label of the input's {timeline.tier!r} interval holding the frame (missing outside)",
            "target": "the target's phone at the frames the synthesis aimed at (missing elsewhere)", name: what}
    if traj.states is not None:
        cols["state"] = np.asarray(traj.states, np.int64)
        units["state"], desc["state"] = "index", "state of the synthesised path"
    table = FrameTable(columns=cols, units=units, descriptions=desc, rate=rate,
                       notes=[f"{name}: {what}", f"method {traj.method}; {len(tf)} targets from {targets.source}"])
    lf, ll = kinematic_landmarks(one, aperture=opening) if n >= 3 else (np.zeros(0, int), np.zeros(0, str))
    tiers = [IntervalTier(timeline.tier, [(p.start, p.end, p.label) for p in timeline.phones]),
             PointTier("targets", [(float(t[f]), str(target[f])) for f in tf[ok]]),
             PointTier("landmarks", [(float(t[f]), str(lab)) for f, lab in zip(lf, ll)])]
    return table, (timeline.xmin, timeline.xmax, tiers)
