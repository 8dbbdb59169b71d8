"""Session files: reopen the explorer on the same data, selection and view.

A session is a small JSON file, written atomically, holding where the manifold came
from (a manifold or corpus file, or the synthetic preset), the selection, colour and
hemisphere modes, the visible phone ellipsoids, the current utterance and the
camera of each 3-D view. Qt-free: cameras are plain lists from the views.
"""
from __future__ import annotations

import json
from pathlib import Path

from engine._atomic import write_text_atomic

__all__ = ["SESSION_VERSION", "SessionError", "session_dict", "save_session", "load_session",
           "apply_session"]

SESSION_VERSION = 1


class SessionError(ValueError):
    """A session file cannot be read or does not fit the loaded manifold."""


def session_dict(state, *, cameras: dict | None = None, extra: dict | None = None) -> dict:
    """The JSON-ready content of a session for ``state``.

    Parameters
    ----------
    state : app.state.AppState
    cameras : dict of str to camera, optional
        ``{"manifold": [[px, py, pz], [fx, fy, fz], [ux, uy, uz]], ...}`` per view.
    extra : dict, optional
        View settings (the editor's text and method, ...), stored as given.
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
        "path_mode": bool(state.path_mode),
        "utterance": state.utterance,
        "visible_phones": sorted(state.visible_phones),
        "component": state.component,
        "cameras": {k: [[float(x) for x in row] for row in v] for k, v in (cameras or {}).items()},
        "extra": dict(extra or {}),
    }


def save_session(state, path, *, cameras: dict | None = None, extra: dict | None = None) -> Path:
    """Write ``state`` (and the views' cameras) to the JSON session file ``path``, atomically."""
    path = Path(path)
    d = session_dict(state, cameras=cameras, extra=extra)
    return write_text_atomic(path, json.dumps(d, indent=2) + "\n")


def load_session(path) -> dict:
    """Read and check a session file; returns the dict :func:`session_dict` wrote."""
    from app.state import COLOR_MODES, HEMISPHERES

    path = Path(path)
    try:
        d = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SessionError(f"{path}: no such session file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise SessionError(f"{path}: not a readable Lipspace session (JSON) file: {exc}") from None
    if not isinstance(d, dict) or "lipspace_session" not in d:
        raise SessionError(f"{path}: not a Lipspace session file (no 'lipspace_session' key)")
    if not isinstance(d["lipspace_session"], int) or d["lipspace_session"] > SESSION_VERSION:
        raise SessionError(f"{path}: session format {d['lipspace_session']!r} is newer than this Lipspace "
                           f"({SESSION_VERSION}); upgrade Lipspace")
    if d.get("color_mode", "density") not in COLOR_MODES:
        raise SessionError(f"{path}: colour mode {d.get('color_mode')!r} is not one of {COLOR_MODES}")
    if d.get("hemisphere", "future") not in HEMISPHERES:
        raise SessionError(f"{path}: hemisphere {d.get('hemisphere')!r} is not one of {HEMISPHERES}")
    sel = d.get("selection", {})
    for k in ("frame", "state", "target"):
        v = sel.get(k)
        if v is not None and (not isinstance(v, int) or isinstance(v, bool) or v < 0):
            raise SessionError(f"{path}: selection {k} must be a non-negative integer or null, got {v!r}")
    d.setdefault("source", {"path": None, "preset": "default"})
    src = d["source"]
    if not isinstance(src, dict):
        raise SessionError(f"{path}: field 'source' must be an object, got {type(src).__name__}")
    if src.get("path") is not None:  # only a data file the user chose; never opened to be checked
        from engine._validate import FieldError, check_source_path

        try:
            src["path"] = str(check_source_path(src["path"], source=path))
        except FieldError as exc:
            raise SessionError(str(exc)) from None
    d.setdefault("cameras", {})
    d.setdefault("extra", {})
    d.setdefault("visible_phones", [])
    d["_file"] = str(path)
    return d


def apply_session(state, d: dict) -> None:
    """Restore a loaded session ``d`` into ``state`` (whose manifold is already loaded).

    Raises :class:`SessionError` when an index does not fit the manifold (the session
    was saved over another manifold).
    """
    where = d.get("_file", "session")
    sel = d.get("selection", {})
    try:
        if d.get("utterance") is not None:
            state.set_utterance(d["utterance"])
        state.set_hemisphere(d.get("hemisphere", "future"))
        state.set_path_mode(d.get("path_mode", False))
        if sel.get("frame") is not None:
            state.select_frame(sel["frame"], as_target=False)
        elif sel.get("state") is not None:
            state.select_state(sel["state"])
        else:
            state.clear_selection()
        if sel.get("target") is not None:
            state.set_target(sel["target"])
        state.set_visible_phones(d.get("visible_phones", []))
        state.set_component(d.get("component"))
        state.set_color_mode(d.get("color_mode", "density"))
    except (IndexError, KeyError) as exc:
        raise SessionError(f"{where}: does not fit the loaded manifold ({exc}); "
                           "was it saved with another corpus or manifold?") from None
