"""A trajectory the explorer shows, as lip frames and as files (Qt-free).

The trajectory editor makes one from key targets with :func:`synthesize_targets` and
scores it with :func:`trajectory_error`; the lip view plays :func:`lip_frames`, the
window's File > Export trajectory writes through :func:`export_trajectory`, the
animation export renders :func:`lip_frames`.
"""
from __future__ import annotations

import glob
from pathlib import Path

import numpy as np

__all__ = ["lip_frames", "trajectory_table", "export_trajectory", "synthesize_targets", "trajectory_error",
           "METHOD_LABELS"]

METHOD_LABELS = {"manifold": "Manifold (max-probability path)", "linear": "Linear interpolation (X)",
                 "cubic": "Cubic spline (X)", "unitselection": "Unit selection"}



def lip_frames(manifold, traj) -> np.ndarray:
    """Frames (n, C) of a trajectory: captured rows for originals, F^x mapped back otherwise.

    ``traj`` is an :class:`app.state.TrajectoryData` of n frames; C = points x dims of
    the manifold's corpus. F^x is mapped back through the shape space; a trajectory with
    only Y goes through the manifold's inverse map first.
    """
    if traj.frames is not None:
        return np.asarray(manifold.corpus_.frames[np.asarray(traj.frames)])
    if traj.Fx is not None:
        return np.asarray(manifold.shape_.inverse_transform(traj.Fx))
    Fx = manifold.inverse_map.transform(np.asarray(traj.Y)[:, :manifold.inverse_map.n_dims])
    return np.asarray(manifold.shape_.inverse_transform(Fx))


def trajectory_table(traj) -> tuple[np.ndarray, list[str]]:
    """The columns a trajectory exports to CSV/NPY: Y1..Y3 (embedding) then X1..Xm (shape).

    Returns (values (n, 3 + m) float32, column names).
    """
    Y = np.asarray(traj.Y, np.float32)[:, :3]
    Fx = np.zeros((len(Y), 0), np.float32) if traj.Fx is None else np.asarray(traj.Fx, np.float32)
    cols = [f"Y{k + 1}" for k in range(Y.shape[1])] + [f"X{k + 1}" for k in range(Fx.shape[1])]
    return np.hstack([Y, Fx]), cols


def export_trajectory(manifold, traj, path) -> list[Path]:
    """Write a trajectory by suffix: ``.csv`` (time, Y1-3, X1-m), ``.npy`` (the same columns
    without time), ``.obj`` / ``.ply`` (lip mesh sequence: ``<stem>_00000.obj`` ... in a
    folder ``<stem>/`` beside ``path``). Returns the files written.
    """
    from engine.io.export import write_mesh_sequence, write_trajectory_csv, write_trajectory_npy

    path = Path(path)
    suf = path.suffix.lower()
    if suf == ".csv":
        values, cols = trajectory_table(traj)
        return [write_trajectory_csv(path, values, rate=traj.rate, columns=cols)]
    if suf == ".npy":
        return [write_trajectory_npy(path, trajectory_table(traj)[0])]
    if suf in (".obj", ".ply"):
        from engine.staging import Outputs

        frames = lip_frames(manifold, traj)
        c = manifold.corpus_
        folder = path.with_suffix("")
        # the save dialog asked about `path`, not about the frame files in the folder: those are never replaced
        with Outputs(hint="Choose another name, or move the existing frame files away first") as outputs:
            tmp = outputs.folder(folder, pattern=f"{glob.escape(path.stem)}_*{suf}", exclusive=True)
            files = write_mesh_sequence(tmp, frames, faces=c.faces, dims=c.dims, format=suf[1:], prefix=path.stem)
        return [folder / f.name for f in files]
    raise ValueError(f"{path}: cannot export a trajectory as {suf or 'a file without a suffix'!r}; "
                     "use .csv, .npy, .obj or .ply")


def synthesize_targets(manifold, targets, method: str, synthesizers: dict | None = None):
    """Run synthesis method ``method`` on ``targets``; returns (TrajectoryData, engine Trajectory).

    The manifold method runs with ``strict=False`` so a target that cannot be reached
    in time is undershot (and said so in the trajectory's warnings) instead of failing.
    ``synthesizers`` caches fitted synthesisers per method.
    """
    from app.state import TrajectoryData
    from engine.synthesis import make_synthesizer

    cache = synthesizers if synthesizers is not None else {}
    if method not in cache:
        params = {"strict": False} if method == "manifold" else {}
        cache[method] = make_synthesizer(method, manifold, **params)
    traj = cache[method].synthesize(targets)
    Y = traj.Fy
    if Y is None:  # methods that move in X: place them in Y out of sample
        Y = manifold.project(traj.frames(manifold))
    data = TrajectoryData(Y=np.asarray(Y, np.float32), Fx=np.asarray(traj.Fx, np.float32), frames=None,
                          label=METHOD_LABELS.get(method, method).split(" (")[0], rate=float(targets.rate),
                          extra={"method": method, "warnings": list(traj.warnings),
                                 "target_frames": np.asarray(traj.target_frames)})
    return data, traj


def trajectory_error(manifold, synthetic, original) -> dict:
    """Error of a synthetic trajectory against the captured original, as ``lipspace evaluate`` scores it.

    The first ``n = min(len(synthetic), len(original))`` frames are compared through
    :func:`engine.evaluation.trajectory_errors`, so the editor's readout and the
    evaluation table are the same numbers. Returns its dict: ``rmse_x`` (root mean
    square over frames of the Euclidean error in X), ``mean_point_error`` and
    ``max_point_error`` (per-point Euclidean error in the corpus's units), ``frames``.
    """
    from engine.evaluation import trajectory_errors

    n = min(len(synthetic), len(original))
    frames = manifold.corpus_.frames[np.asarray(original.frames[:n])]
    return trajectory_errors(manifold, np.asarray(synthetic.Fx[:n]), frames)
