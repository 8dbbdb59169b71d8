"""File › Export animation: what the explorer shows, as a glTF animation or an MP4 (Qt-free).

The trajectory exported is the one File › Export trajectory writes: the synthetic one
if there is one, else the selected utterance's original. The utterance's audio goes
with it when the trajectory runs on the utterance's own timeline (the original, or a
re-synthesis of the same length), and a synthesis of typed text carries the text spoken
(``extra["audio"]``, :mod:`app.files.sound`); an MP4 of a synthetic trajectory shows the original
beside it and the manifold panel with both paths, as the lip view and manifold view do.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["export_current_animation", "ANIMATION_SUFFIXES"]

ANIMATION_SUFFIXES = (".glb", ".gltf", ".mp4")


def _fx(manifold, traj):
    if traj.Fx is not None:
        return np.asarray(traj.Fx, np.float32)
    inv = manifold.inverse_map
    return np.asarray(inv.transform(np.asarray(traj.Y)[:, :inv.n_dims]), np.float32)


def export_current_animation(state, path, *, size=(640, 480), progress=None) -> list[Path]:
    """Write the current trajectory of an :class:`app.models.state.AppState` by suffix.

    Parameters
    ----------
    state : app.models.state.AppState
        With a manifold and an original or synthetic trajectory.
    path : str or Path
        ``.glb`` / ``.gltf`` (morph animation, WAV beside it) or ``.mp4`` (video).
    size : (int, int)
        MP4: pixels of one panel.
    progress : callable, optional
        MP4: ``progress("render", done, total)``; raising from it cancels (nothing written).

    Returns
    -------
    list of Path
        The files written.
    """
    from app.export.animation import export_animation, utterance_audio
    from app.models.trajectories import lip_frames

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in ANIMATION_SUFFIXES:
        raise ValueError(f"{path}: an animation is written as .glb, .gltf or .mp4, not {suffix or 'no suffix'!r}")
    m = state.manifold
    traj = state.synthetic if state.synthetic is not None else state.original
    if m is None or traj is None:
        raise ValueError("no trajectory to export: choose an utterance or synthesise one in the trajectory editor")
    audio = None
    if state.utterance is not None and state.original is not None and len(traj) == len(state.original):
        audio, _why = utterance_audio(m, state.utterance, state.source.get("path"))
    elif traj is state.synthetic and (traj.extra or {}).get("audio"):  # typed text, spoken
        from app.files.sound import resolve_audio_path

        audio = resolve_audio_path(traj.extra["audio"])
    if suffix in (".glb", ".gltf"):
        return export_animation(m, _fx(m, traj), path, rate=traj.rate, audio=audio, source=traj.label)
    from app.export.video import render_video

    two = state.synthetic is not None and state.original is not None
    original = lip_frames(m, state.original) if two else None
    c = m.corpus_
    from engine.recordings.orientation import anatomical_frame

    return [render_video(path, lip_frames(m, traj), rate=traj.rate, faces=c.faces, dims=c.dims,
                         orientation=anatomical_frame(c, m.shape_.mean_), unit=c.unit_label,
                         roles=c.point_roles or None, names=c.point_names or None, original=original,
                         Y=np.asarray(traj.Y)[:, :3],
                         Y_original=np.asarray(state.original.Y)[:, :3] if two else None, cloud=m.Fy_[:, :3],
                         audio=audio, size=size, title=traj.label, progress=progress)]
