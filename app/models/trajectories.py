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

from engine.synthesis.methods import SYNTHESIS_METHODS

__all__ = ["lip_frames", "trajectory_table", "export_trajectory", "synthesize_targets", "trajectory_error",
           "METHOD_LABELS", "resolve_method", "method_params", "needs_choice", "stale_choice_note"]

#: the method menu's entries: "best", then each method of the registry (engine.synthesis.methods)
METHOD_LABELS = {"best": "Best on validation (per corpus)", **{name: m.label for name, m in SYNTHESIS_METHODS.items()}}
#: methods that need the corpus's validated settings (engine.synthesis.method_choice)
_VALIDATED = tuple(name for name, m in SYNTHESIS_METHODS.items() if m.build == "validated")


def needs_choice(method: str) -> bool:
    """Whether ``method`` (a method name or ``"best"``) reads the corpus's validated choice."""
    return method == "best" or method in _VALIDATED or method == "sliding-window"


def stale_choice_note(manifold, name: str, *, short: bool = False) -> str | None:
    """What to tell about a manifold file whose stored synthesis choice other code measured (an older
    Lipspace; :func:`engine.synthesis.method_choice.stored_choice` ignores it), or None when its choice is
    current or none is stored. ``name`` names the file in the note; ``short``: a line that fits a status
    bar beside the window's summary."""
    from engine.synthesis.stored_choice import stored_choice

    if not isinstance(getattr(manifold, "synthesis_choice_", None), dict) or stored_choice(manifold) is not None:
        return None
    if short:
        return f"{name}: synthesis choice from older code: rebuild with 'lipspace build'"
    return (f"{name} stores a synthesis choice that other code measured (an older Lipspace): the first "
            "synthesis measures it again (then it is cached) and the chosen synthesiser is fitted anew each time; "
            "build the manifold again ('lipspace build') to store current ones in the file")


def _choice(manifold, cache, progress=None):
    """The corpus's validated method choice, measured once (engine.synthesis.method_choice; cached on disk too)."""
    if "_choice" not in cache:
        from engine.synthesis.method_choice import choose_methods

        cache["_choice"] = choose_methods(manifold, progress=progress)
    return cache["_choice"]


def resolve_method(manifold, targets, method: str, cache: dict, progress=None):
    """``(method, note)``: ``"best"`` becomes the method measured best on the corpus's validation
    split for the protocol of ``targets``, ``note`` naming it ("method: dominance, best on
    validation (...)"); any other method is returned as given with note None."""
    from engine.synthesis.method_choice import BEST, best_method, describe, target_protocol

    if method != BEST:
        return method, None
    choice = _choice(manifold, cache, progress)
    protocol = target_protocol(targets) if targets is not None else "states"
    chosen = best_method(choice, protocol)
    return chosen, describe(choice, protocol, chosen)


def method_params(manifold, method: str, cache: dict, progress=None) -> dict:
    """Constructor parameters of ``method`` for the explorer and the command line: the validated
    settings for the manifold's own methods and the sliding-window regression, undershooting
    (``strict=False``) for the paper's path."""
    if method in _VALIDATED:
        return {"choice": _choice(manifold, cache, progress)}
    if method == "viterbi":
        return {"strict": False}
    if method == "sliding-window":
        from engine.synthesis.method_choice import load_choice

        ch = cache.get("_choice") or load_choice(manifold)
        if ch and ch.get("sliding_window"):
            ctx, ow, alpha = ch["sliding_window"]
            return {"context": int(ctx), "output_window": int(ow), "alpha": float(alpha)}
    return {}



def lip_frames(manifold, traj) -> np.ndarray:
    """Frames (n, C) of a trajectory: captured rows for originals, F^x mapped back otherwise.

    ``traj`` is an :class:`app.models.state.TrajectoryData` of n frames; C = points x dims of
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
    from engine.io.writers.export import write_mesh_sequence, write_trajectory_csv, write_trajectory_npy

    path = Path(path)
    suf = path.suffix.lower()
    if suf == ".csv":
        values, cols = trajectory_table(traj)
        return [write_trajectory_csv(path, values, rate=traj.rate, columns=cols)]
    if suf == ".npy":
        return [write_trajectory_npy(path, trajectory_table(traj)[0])]
    if suf in (".obj", ".ply"):
        from engine.files.staging import Outputs

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


def synthesize_targets(manifold, targets, method: str, synthesizers: dict | None = None, progress=None):
    """Run synthesis method ``method`` (or ``"best"``) on ``targets``; returns (TrajectoryData, engine Trajectory).

    ``"best"`` takes the method measured best on the corpus's validation split for these
    targets (:func:`resolve_method`); the data's ``extra["method_note"]`` names it. The
    paper's path (``"viterbi"``) runs with ``strict=False`` so a target that cannot be
    reached in time is undershot (and said so in the trajectory's warnings) instead of
    failing. ``synthesizers`` caches fitted synthesisers per method (and the validated
    choice); ``progress`` sees the validation when it has to run.
    """
    from app.models.state import TrajectoryData
    from engine.synthesis.methods import make_synthesizer

    cache = synthesizers if synthesizers is not None else {}
    method, note = resolve_method(manifold, targets, method, cache, progress)
    if method not in cache:
        cache[method] = make_synthesizer(method, manifold, **method_params(manifold, method, cache, progress))
    traj = cache[method].synthesize(targets)
    Y = traj.Fy
    if Y is None:  # methods that move in X: place them in Y out of sample
        Y = manifold.project(traj.frames(manifold))
    data = TrajectoryData(Y=np.asarray(Y, np.float32), Fx=np.asarray(traj.Fx, np.float32), frames=None,
                          label=METHOD_LABELS.get(method, method).split(" (")[0], rate=float(targets.rate),
                          extra={"method": method, "method_note": note, "warnings": list(traj.warnings),
                                 "target_frames": np.asarray(traj.target_frames),
                                 # what the exports put on the timeline (app.export.trajectory)
                                 "targets": targets, "trajectory": traj})
    return data, traj


def trajectory_error(manifold, synthetic, original) -> dict:
    """Error of a synthetic trajectory against the captured original.

    The first ``n = min(len(synthetic), len(original))`` frames are compared through
    :func:`engine.evaluation.measures.trajectory_errors`; its RMSE in X is the one
    ``lipspace evaluate`` reports per protocol and method. Returns its dict: ``rmse_x`` (root mean
    square over frames of the Euclidean error in X), ``mean_point_error`` and
    ``max_point_error`` (per-point Euclidean error in the corpus's units), ``frames``.
    """
    from engine.evaluation.measures import trajectory_errors

    n = min(len(synthetic), len(original))
    frames = manifold.corpus_.frames[np.asarray(original.frames[:n])]
    return trajectory_errors(manifold, np.asarray(synthetic.Fx[:n]), frames)
