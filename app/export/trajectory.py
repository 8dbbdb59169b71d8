"""The window's trajectory exports: a tidy table as complete as ``lipspace synthesize``'s, and a TextGrid.

File › Export trajectory writes the trajectory the window shows (the synthesised one, else the
captured utterance) as one row per frame: time, the phone and target at it, the lip points'
coordinates (the corpus's point names and unit, as ``lipspace synthesize -o`` writes them), the
opening measure, the state, F^y and F^x; units and column meanings go to a JSON file beside it
(:func:`engine.io.writers.tidy.write_frame_table`, the writer of ``lipspace table``, so R and pandas
read it without options). ``.npy`` holds the point coordinates alone; ``.obj`` / ``.ply`` a mesh
sequence (:func:`app.models.trajectories.export_trajectory`).

File › Export synthesis as TextGrid writes a synthesised utterance for Praat: its phones, the
targets and the synthesised opening's kinematic landmarks (:func:`engine.synthesis.tiers.synthesis_outputs`,
what ``lipspace synthesize --praat`` writes); a captured utterance gets its phones, movement classes
and landmarks (:func:`engine.manifold.frame_table.utterance_tiers`, what ``lipspace table --textgrid``
writes).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["trajectory_table", "export_trajectory", "export_textgrid", "TABLE_SUFFIXES", "TRAJECTORY_SUFFIXES"]

#: tables (with their units beside them)
TABLE_SUFFIXES = (".csv", ".parquet")
#: everything File › Export trajectory writes
TRAJECTORY_SUFFIXES = (".csv", ".parquet", ".npy", ".obj", ".ply")


def _synthesis(traj):
    """``(targets, engine trajectory)`` of a synthesised trajectory (the editor keeps them), or None."""
    extra = getattr(traj, "extra", None) or {}
    if extra.get("targets") is not None and extra.get("trajectory") is not None:
        return extra["targets"], extra["trajectory"]
    return None


def trajectory_table(manifold, traj):
    """One row per frame of ``traj`` (:class:`app.models.state.TrajectoryData`) as a
    :class:`engine.manifold.frame_table.FrameTable` (see the module docstring).

    A synthesised trajectory takes its columns ``time_s, frame, phone, target, <opening>, state`` from
    :func:`engine.synthesis.tiers.synthesis_outputs`; a captured one ``utterance, time_s, frame, phone``
    from the corpus. Then every point's coordinates (``<point>_x``, ...: the corpus's axes and unit, as
    ``lipspace synthesize -o`` writes them), ``y_1..y_3`` and ``x_1..x_m``.
    """
    from app.models.trajectories import lip_frames
    from engine.io.writers.export import corpus_columns
    from engine.manifold.frame_table import FrameTable

    c = manifold.corpus_
    n = len(traj)
    rate = float(traj.rate)
    syn = _synthesis(traj)
    if syn is not None:
        from engine.synthesis.tiers import synthesis_outputs

        table, _grid = synthesis_outputs(manifold, *syn)
        cols, units, desc = dict(table.columns), dict(table.units), dict(table.descriptions)
        notes = list(table.notes)
    elif traj.frames is not None:  # a captured utterance: its own phones
        from engine.manifold.frame_table import frame_table

        whole = frame_table(manifold, n_fx=0)
        rows = np.asarray(traj.frames, np.int64)
        keep = ("utterance", "speaker", "time_s", "frame", "phone", "landmark")
        cols = {k: np.asarray(whole.columns[k])[rows] for k in keep}
        units = {k: whole.units[k] for k in keep}
        desc = {k: whole.descriptions[k] for k in keep}
        notes = [f"the captured utterance {traj.label}"]
    else:
        cols = {"time_s": np.arange(n) / rate, "frame": np.arange(n)}
        units = {"time_s": "s", "frame": f"frames at {rate:g} Hz"}
        desc = {"time_s": "time from the start of the trajectory", "frame": "frame, from 0"}
        notes = []
    frames = np.asarray(lip_frames(manifold, traj), np.float64)
    for j, name in enumerate(corpus_columns(c)):
        cols[name] = frames[:, j]
        units[name] = c.unit_label
        point, axis = name.rsplit("_", 1)
        desc[name] = f"{axis} coordinate of point {point}, in the corpus's own axes (as recorded)"
    Y = np.asarray(traj.Y, np.float64)
    for j in range(min(3, Y.shape[1])):
        cols[f"y_{j + 1}"], units[f"y_{j + 1}"] = Y[:, j], "embedding units (F^y)"
        desc[f"y_{j + 1}"] = f"manifold coordinate F^y_{j + 1}"
    if traj.Fx is not None:
        Fx = np.asarray(traj.Fx, np.float64)
        for j in range(Fx.shape[1]):
            cols[f"x_{j + 1}"], units[f"x_{j + 1}"] = Fx[:, j], "shape-space units (F^x)"
            desc[f"x_{j + 1}"] = f"shape coordinate F^x_{j + 1}"
    label = traj.label or "trajectory"
    notes.append(f"{label}: {n} frames at {rate:g} Hz of {c.name}")
    return FrameTable(columns=cols, units=units, descriptions=desc, notes=notes, rate=rate, source=label)


def export_trajectory(manifold, traj, path) -> list[Path]:
    """Write ``traj`` to ``path`` by suffix (see the module docstring); returns the files written."""
    path = Path(path)
    suf = path.suffix.lower()
    if suf in TABLE_SUFFIXES:
        from engine.io.writers.tidy import write_frame_table

        return write_frame_table(path, trajectory_table(manifold, traj))
    if suf == ".npy":
        from app.models.trajectories import lip_frames
        from engine.io.writers.export import write_trajectory_npy

        return [write_trajectory_npy(path, lip_frames(manifold, traj))]
    if suf in (".obj", ".ply"):
        from app.models.trajectories import export_trajectory as export_mesh

        return export_mesh(manifold, traj, path)
    raise ValueError(f"{path}: cannot export a trajectory as {suf or 'a file without a suffix'!r}; "
                     f"use {', '.join(TRAJECTORY_SUFFIXES)}")


def export_textgrid(manifold, traj, path) -> Path:
    """Write ``traj`` as a Praat TextGrid (see the module docstring)."""
    from engine.io.writers.praat import write_textgrid

    path = Path(path)
    if path.suffix.lower() != ".textgrid":
        raise ValueError(f"{path}: a TextGrid file ends in .TextGrid")
    syn = _synthesis(traj)
    if syn is not None:
        from engine.synthesis.tiers import synthesis_outputs

        _table, (xmin, xmax, tiers) = synthesis_outputs(manifold, *syn)
        return write_textgrid(path, xmin, xmax, tiers)
    if traj.frames is not None:
        from engine.manifold.frame_table import frame_table, utterance_tiers

        uid = manifold.corpus_.utterance_index[int(np.asarray(traj.frames)[0])]
        u = manifold.corpus_.utterances[int(uid)]
        xmin, xmax, tiers = utterance_tiers(manifold, frame_table(manifold, n_fx=0), u.id)
        return write_textgrid(path, xmin, xmax, tiers)
    raise ValueError(f"the trajectory {traj.label!r} has neither its targets nor corpus frames: nothing to align a "
                     "TextGrid with; synthesise it again in the trajectory editor")
