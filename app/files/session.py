"""Session files: reopen the explorer on the same data, selection and view.

A session is a small JSON file, written atomically, holding where the manifold came
from (a manifold or corpus file, or the synthetic preset), the selection, colour and
hemisphere modes, the visible phone ellipsoids and their opacity, the hidden layers, the
session palette (so each category keeps its colour), the current utterance and the
camera of each 3-D view. Qt-free: cameras are plain lists from the views.

The synthesised trajectory and the trajectory editor's key targets (as edited, e.g.
dragged) are arrays: they go to an ``.npz`` beside the JSON (``a.lipspace.json`` ->
``a.lipspace.npz``), written with the JSON as one transaction (both or neither), and
the JSON holds that file's name and SHA-256, so a JSON never silently pairs with
another save's arrays.
Their labels, phones and settings stay in the JSON.
"""
from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path

import numpy as np

from app.files.session_schema import SessionError, check_session
from engine.files.atomic import atomic_write, write_text_atomic

__all__ = ["SESSION_VERSION", "SessionError", "session_dict", "session_arrays", "arrays_path", "save_session",
           "load_session", "apply_session", "source_kinematics"]

#: 2 added the synthesised trajectory and edited targets (.npz beside); 1 is still read
SESSION_VERSION = 2


#: the largest session JSON read (a session of a 10-minute synthesis with edited targets is < 1 MB)
MAX_SESSION_BYTES = 64 * 2**20


def session_dict(state, *, cameras: dict | None = None, extra: dict | None = None, targets=None) -> dict:
    """The JSON-ready content of a session for ``state`` (arrays: :func:`session_arrays`).

    Parameters
    ----------
    state : app.models.state.AppState
    cameras : dict of str to camera, optional
        ``{"manifold": [[px, py, pz], [fx, fy, fz], [ux, uy, uz]], ...}`` per view.
    extra : dict, optional
        View settings (the editor's text and method, ...), stored as given.
    targets : engine.phonetics.targets.TargetSequence, optional
        The trajectory editor's key targets (as edited).
    """
    src = dict(state.source)
    if src.get("path") is not None:
        src["path"] = str(Path(src["path"]).resolve())
    return {
        "lipspace_session": SESSION_VERSION,
        "source": src,
        "selection": {"frame": state.frame, "state": state.state, "target": state.target},
        "color_mode": state.color_mode,
        "hemisphere": state.hemisphere,
        "horizon_ms": state.horizon_ms,
        "phone_filter": sorted(state.phone_filter),
        "path_mode": bool(state.path_mode),
        "utterance": state.utterance,
        "visible_phones": sorted(state.visible_phones),
        "ellipsoid_opacity": float(state.ellipsoid_opacity),
        "hidden_layers": sorted(state.hidden_layers),
        "color_field": state.color_field,
        "field_filter": [list(p) for p in sorted(state.field_filter)],
        "palette": None if state.palette is None else state.palette.to_dict(),
        "component": state.component,
        "cameras": {k: [[float(x) for x in row] for row in v] for k, v in (cameras or {}).items()},
        "extra": dict(extra or {}),
        "synthetic": _trajectory_meta(state.synthetic),
        "targets": _targets_meta(targets),
    }


def _trajectory_meta(traj) -> dict | None:
    if traj is None:
        return None
    ex = traj.extra or {}
    return {"label": str(traj.label), "rate": float(traj.rate), "method": ex.get("method"),
            "warnings": [str(w) for w in ex.get("warnings") or []]}


def _targets_meta(targets) -> dict | None:
    if targets is None:
        return None
    return {"labels": [str(t.label) for t in targets.targets],
            "phones": [[float(p.start), float(p.end), str(p.label)] for p in targets.phones],
            "n_frames": int(targets.n_frames), "rate": float(targets.rate), "source": str(targets.source),
            "utterance": targets.utterance}


def _rows(values, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Stack optional vectors into (n, width) float64 with a mask of which were given."""
    have = np.array([v is not None for v in values], dtype=bool)
    out = np.full((len(values), width), np.nan)
    for i, v in enumerate(values):
        if v is not None:
            out[i] = np.asarray(v, np.float64).reshape(-1)
    return out, have


def session_arrays(state, *, targets=None) -> dict:
    """The arrays of a session: the synthesised trajectory and the key targets (empty if neither)."""
    out = {}
    syn = state.synthetic
    if syn is not None:
        out["synthetic_Y"] = np.asarray(syn.Y, np.float32)
        if syn.Fx is not None:
            out["synthetic_Fx"] = np.asarray(syn.Fx, np.float32)
        if syn.frames is not None:
            out["synthetic_frames"] = np.asarray(syn.frames, np.int64)
        tf = (syn.extra or {}).get("target_frames")
        if tf is not None:
            out["synthetic_target_frames"] = np.asarray(tf, np.int64)
    if targets is not None:
        ts = targets.targets
        out["targets_frame"] = np.array([t.frame for t in ts], np.int64)
        out["targets_state"] = np.array([-1 if t.state is None else int(t.state) for t in ts], np.int64)
        for key in ("y", "x"):
            vals = [getattr(t, key) for t in ts]
            width = max((np.asarray(v).size for v in vals if v is not None), default=0)
            out[f"targets_{key}"], out[f"targets_{key}_given"] = _rows(vals, width)
    return out


def arrays_path(path) -> Path:
    """The ``.npz`` beside session file ``path`` (``a.lipspace.json`` -> ``a.lipspace.npz``)."""
    path = Path(path)
    stem = path.name[:-5] if path.name.lower().endswith(".json") else path.name
    return path.with_name(stem + ".npz")


def save_session(state, path, *, cameras: dict | None = None, extra: dict | None = None, targets=None) -> Path:
    """Write ``state`` (and the views' cameras) to the JSON session file ``path``, atomically.

    The synthesised trajectory and ``targets`` go to :func:`arrays_path` first (also
    atomically); the JSON names it with its SHA-256. Returns the JSON file.
    """
    path = Path(path)
    if path.suffix.lower() == ".npz":
        raise ValueError(f"{path}: a session file is JSON; name it <name>.lipspace.json (its arrays go to "
                         "<name>.lipspace.npz beside it)")
    d = session_dict(state, cameras=cameras, extra=extra, targets=targets)
    arrays = session_arrays(state, targets=targets)
    npz = arrays_path(path)
    from engine.files.staging import Outputs

    with Outputs(force=True) as outputs:  # the JSON and its arrays together, or neither
        if arrays:
            buf = io.BytesIO()
            np.savez(buf, **arrays)
            data = buf.getvalue()
            with atomic_write(outputs.file(npz)) as tmp:
                tmp.write_bytes(data)
            d["arrays"] = {"file": npz.name, "sha256": hashlib.sha256(data).hexdigest()}
        write_text_atomic(outputs.file(path), json.dumps(d, indent=2) + "\n")
    if not arrays and npz.is_file() and npz != path:
        npz.unlink(missing_ok=True)  # an earlier save's arrays no longer belong to this session
    return path


def load_session(path) -> dict:
    """Read and check a session file; returns the dict :func:`session_dict` wrote.

    The file is read only when it is a regular file of at most :data:`MAX_SESSION_BYTES`
    (a FIFO, ``/dev/zero`` behind a link or a huge file is refused before reading), and
    every field is checked against :func:`app.files.session_schema.check_session` before
    anything uses it. Raises :class:`SessionError` naming the file and the field.
    """
    from engine.files.bounded import parse_json, read_bounded

    path = Path(path)
    try:
        raw = read_bounded(path, limit=MAX_SESSION_BYTES, what="session file")
        d = parse_json(raw, source=path, what="a Lipspace session (JSON)")
    except FileNotFoundError:
        raise SessionError(f"{path}: no such session file") from None
    except (OSError, ValueError) as exc:
        why = str(exc).removeprefix(f"{path}: ")
        raise SessionError(f"{path}: not a readable Lipspace session (JSON) file: {why}") from None
    if not isinstance(d, dict) or "lipspace_session" not in d:
        raise SessionError(f"{path}: not a Lipspace session file (no 'lipspace_session' key)")
    version = d["lipspace_session"]
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise SessionError(f"{path}: field 'lipspace_session' must be a format number (1 or more), got "
                           f"{json.dumps(version)[:40]}; the session file is damaged")
    if version > SESSION_VERSION:
        raise SessionError(f"{path}: session format {version!r} is newer than this Lipspace ({SESSION_VERSION}); "
                           "upgrade Lipspace")
    d = check_session(d, path)
    src = d["source"]
    if "kinematics" in src:  # the synthetic talker's (absent from sessions written before it had a choice)
        from app.files.source_loading import check_kinematics

        try:
            check_kinematics(src["kinematics"])
        except ValueError as exc:
            raise SessionError(f"{path}: source {exc}") from None
    if src.get("path") is not None:  # only a data file the user chose; never opened to be checked
        from engine.files.validate import FieldError, check_source_path

        try:
            src["path"] = str(check_source_path(src["path"], source=path))
        except FieldError as exc:
            raise SessionError(str(exc)) from None
    d["_file"] = str(path)
    d["_synthetic"], d["_targets"] = _read_arrays(path, d)
    return d


def source_kinematics(d: dict) -> str:
    """The synthetic talker's kinematics session ``d`` was saved with: ``"classic"`` for a
    file's session and for a session written before the talker had a choice (no key)."""
    src = d.get("source", {})
    return "classic" if src.get("path") is not None else src.get("kinematics", "classic")


def _read_arrays(path: Path, d: dict):
    """The session's (TrajectoryData or None, TargetSequence or None) from its .npz."""
    from engine.files.persist import NpzReadError, read_npz

    ref = d.get("arrays")
    if not ref:
        if d.get("synthetic") or d.get("targets"):
            raise SessionError(f"{path}: names a synthesised trajectory or targets but no arrays file")
        return None, None
    name = ref.get("file") if isinstance(ref, dict) else None
    if not isinstance(name, str) or Path(name).name != name or not name.endswith(".npz"):
        raise SessionError(f"{path}: arrays file must be a plain .npz file name beside the session, got {name!r}")
    npz = path.with_name(name)
    from engine.files.bounded import BINARY_EXPANSION, input_limit, read_bounded

    try:  # a regular file that fits in memory: never a FIFO (it would hang) or /dev/zero (it never ends)
        data = read_bounded(npz, limit=input_limit(BINARY_EXPANSION)[0], what="session arrays file")
    except (OSError, ValueError) as exc:
        why = str(exc).removeprefix(f"{npz}: ") if str(exc).startswith(str(npz)) else (
            getattr(exc, "strerror", None) or str(exc))
        raise SessionError(f"{path}: its arrays file {npz} cannot be read ({why}); keep the .npz beside the "
                           "session file") from None
    if hashlib.sha256(data).hexdigest() != ref.get("sha256"):
        raise SessionError(f"{path}: its arrays file {npz} does not match the session (SHA-256 differs): it was "
                           "overwritten by another save or damaged")
    try:
        a = read_npz(npz)
    except (NpzReadError, FileNotFoundError) as exc:
        raise SessionError(str(exc)) from None
    try:
        return _trajectory_from(a, d.get("synthetic")), _targets_from(a, d.get("targets"))
    except (KeyError, ValueError, TypeError, IndexError) as exc:
        raise SessionError(f"{npz}: session arrays are inconsistent with {path.name} ({exc})") from None


def _trajectory_from(a: dict, meta):
    from app.models.state import TrajectoryData

    if meta is None:
        return None
    Y = np.asarray(a["synthetic_Y"], np.float32)
    Fx = a.get("synthetic_Fx")
    frames = a.get("synthetic_frames")
    if Y.ndim != 2 or Y.shape[0] == 0:
        raise ValueError(f"synthetic_Y must be (n > 0, k), got shape {Y.shape}")
    for name, v in (("synthetic_Fx", Fx), ("synthetic_frames", frames)):
        if v is not None and len(v) != len(Y):
            raise ValueError(f"{name} has {len(v)} rows, synthetic_Y {len(Y)}")
    extra = {"method": meta.get("method"), "warnings": list(meta.get("warnings") or [])}
    if "synthetic_target_frames" in a:
        extra["target_frames"] = np.asarray(a["synthetic_target_frames"], np.int64)
    return TrajectoryData(Y=Y, Fx=None if Fx is None else np.asarray(Fx, np.float32), frames=frames,
                          label=str(meta.get("label", "")), rate=float(meta["rate"]), extra=extra)


def _targets_from(a: dict, meta):
    from engine.phonetics.targets import Target, TargetSequence
    from engine.recordings.corpus import PhoneInterval

    if meta is None:
        return None
    frames, states, labels = a["targets_frame"], a["targets_state"], list(meta["labels"])
    n = len(frames)
    if len(states) != n or len(labels) != n or len(a["targets_y"]) != n or len(a["targets_x"]) != n:
        raise ValueError(f"{n} target frames but {len(states)} states, {len(labels)} labels")
    if n and np.any(np.diff(frames) <= 0):
        raise ValueError("target frames must strictly increase")
    ts = tuple(Target(int(f), str(lab), None if s < 0 else int(s),
                      a["targets_y"][i].copy() if a["targets_y_given"][i] else None,
                      a["targets_x"][i].copy() if a["targets_x_given"][i] else None)
               for i, (f, s, lab) in enumerate(zip(frames, states, labels)))
    phones = tuple(PhoneInterval(float(p[0]), float(p[1]), str(p[2])) for p in meta["phones"])
    return TargetSequence(targets=ts, phones=phones, n_frames=int(meta["n_frames"]), rate=float(meta["rate"]),
                          source=str(meta.get("source", "")), utterance=meta.get("utterance"))


def apply_session(state, d: dict):
    """Restore a loaded session ``d`` into ``state`` (whose manifold is already loaded).

    Also restores the synthesised trajectory. Returns the session's key targets
    (:class:`engine.phonetics.targets.TargetSequence` or None) for the trajectory editor.

    Raises :class:`SessionError` when an index or a dimension does not fit the
    manifold (the session was saved over another manifold).
    """
    where = d.get("_file", "session")
    sel = d.get("selection", {})
    try:
        if d.get("utterance") is not None:
            state.set_utterance(d["utterance"])
        state.set_hemisphere(d.get("hemisphere", "future"))
        state.set_horizon(d.get("horizon_ms", state.horizon_ms))  # older sessions: the current horizon
        state.set_phone_filter(d.get("phone_filter", []))
        state.set_path_mode(d.get("path_mode", False))
        if sel.get("frame") is not None:
            state.select_frame(sel["frame"], as_target=False)
        elif sel.get("state") is not None:
            state.select_state(sel["state"])
        else:
            state.clear_selection()
        if sel.get("target") is not None:
            state.set_target(sel["target"])
        if d.get("palette") is not None:  # the colours the session was seen in (older sessions: the corpus's)
            from app.models.palette import SessionPalette

            state.set_palette(SessionPalette.from_dict(d["palette"]))
        state.set_visible_phones(d.get("visible_phones", []))
        state.set_ellipsoid_opacity(d.get("ellipsoid_opacity", state.ellipsoid_opacity))
        state.set_hidden_layers(d.get("hidden_layers", []))
        state.set_component(d.get("component"))
        state.set_color_field(d.get("color_field"))
        state.set_field_filter(d.get("field_filter", []))
        state.set_color_mode(d.get("color_mode", "density"))
        syn, targets = d.get("_synthetic"), d.get("_targets")
        _check_fits(state.manifold, syn, targets)
        if syn is not None:
            state.set_trajectories(synthetic=syn)
    except (IndexError, KeyError, TypeError, ValueError) as exc:  # wrong types too: one dialog, no traceback
        raise SessionError(f"{where}: does not fit the loaded manifold ({exc}); "
                           "was it saved with another corpus or manifold?") from None
    return targets


def _check_fits(m, syn, targets) -> None:
    """IndexError when the trajectory or targets do not fit manifold ``m``."""
    k, mx = int(m.Fy_.shape[1]), int(m.shape_.n_components_)
    if syn is not None:
        if not min(3, k) <= syn.Y.shape[1] <= k:  # a path on the 3-D manifold, or all k dims
            raise IndexError(f"synthesised trajectory has {syn.Y.shape[1]} embedding dims, the manifold {k}")
        if syn.Fx is not None and syn.Fx.shape[1] != mx:
            raise IndexError(f"synthesised trajectory has {syn.Fx.shape[1]} shape components, the manifold {mx}")
        if syn.frames is not None and len(syn.frames) and not 0 <= int(np.min(syn.frames)) <= int(
                np.max(syn.frames)) < m.Fy_.shape[0]:
            raise IndexError(f"synthesised trajectory frames outside 0..{m.Fy_.shape[0] - 1}")
    if targets is not None:
        K = int(m.states_.centroids_.shape[0])
        for t in targets.targets:
            if t.state is not None and not 0 <= t.state < K:
                raise IndexError(f"target at frame {t.frame} has state {t.state}, the manifold has {K}")
            if t.y is not None and t.y.shape[0] > k:
                raise IndexError(f"target at frame {t.frame} has {t.y.shape[0]} embedding dims, the manifold {k}")
            if t.x is not None and t.x.shape[0] != mx:
                raise IndexError(f"target at frame {t.frame} has {t.x.shape[0]} shape components, the manifold {mx}")
