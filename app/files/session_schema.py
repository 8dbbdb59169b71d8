"""The one schema every session file (saved or autosaved) is checked against before any field is used.

A session comes from disk, so every field is untrusted: a dead run's autosave with
``"selection": "x"`` made every start die with a traceback before it could be set
aside. :func:`check_session` walks the JSON against :data:`SESSION` and raises one
:class:`SessionError` naming the file and the field (``selection.frame``), what it must
be and what it holds; missing optional fields get their defaults, fields this version
does not know are left alone (a newer minor format), and nothing else is read. Sizes are
bounded too: lists of at most :data:`MAX_ITEMS` items, strings of at most
:data:`MAX_TEXT` characters.
"""
from __future__ import annotations

import json
import math
import re

__all__ = ["SessionError", "check_session", "json_type", "MAX_ITEMS", "MAX_TEXT"]

#: the longest list a session field may hold (target labels, phones, shown phones ...)
MAX_ITEMS = 1_000_000
#: the longest string a session field may hold (editor text, labels, paths)
MAX_TEXT = 100_000
#: the most frames a session's targets may span (an hour at 2 kHz)
MAX_FRAMES = 7_200_000


class SessionError(ValueError):
    """A session file cannot be read or does not fit the loaded manifold."""


def json_type(v) -> str:
    """How JSON names the type of ``v`` (for messages about a session file)."""
    return {dict: "an object", list: "an array", str: "a string", bool: "true/false", type(None): "null"}.get(
        type(v), "a number")


class _Bad(Exception):
    """A field that does not hold what the schema says: (field path, what it must be, the value)."""

    def __init__(self, field, what, value):
        super().__init__(field)
        self.field, self.what, self.value = field, what, value


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _integer(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


# ---------------------------------------------------------------------------- field kinds
def text(*, null=False, choices=None, what=None, pattern=None):
    """A string (at most MAX_TEXT characters; one of ``choices``; matching ``pattern``)."""
    desc = what or ("one of " + ", ".join(map(repr, choices)) if choices else "a string")

    def check(v, field):
        if v is None and null:
            return None
        if not isinstance(v, str) or len(v) > MAX_TEXT or (choices and v not in choices) or \
                (pattern and not re.fullmatch(pattern, v)):
            raise _Bad(field, desc + (" or null" if null else ""), v)
        return v
    return check


def whole(lo=0, hi=None, *, null=False, what=None):
    desc = what or (f"a whole number >= {lo}" if hi is None else f"a whole number from {lo} to {hi}")

    def check(v, field):
        if v is None and null:
            return None
        if not _integer(v) or v < lo or (hi is not None and v > hi):
            raise _Bad(field, desc + (" or null" if null else ""), v)
        return v
    return check


def number(lo=None, hi=None, *, above=False, null=False, what=None):
    desc = what or ("a finite number" + (f" {'above' if above else '>='} {lo:g}" if lo is not None else "") +
                    (f" and at most {hi:g}" if hi is not None else ""))

    def check(v, field):
        if v is None and null:
            return None
        if not _number(v) or (lo is not None and (v <= lo if above else v < lo)) or (hi is not None and v > hi):
            raise _Bad(field, desc + (" or null" if null else ""), v)
        return v
    return check


def boolean(v, field):
    if not isinstance(v, bool):
        raise _Bad(field, "true or false", v)
    return v


def array(item, *, what, max_items=MAX_ITEMS):
    def check(v, field):
        if not isinstance(v, list) or len(v) > max_items:
            raise _Bad(field, what, v)
        return [item(x, f"{field}[{k}]") for k, x in enumerate(v)]
    return check


def record(fields: dict, *, null=False, what="an object"):
    """A JSON object: each of ``fields`` (name -> (kind, default)) checked, missing ones defaulted."""

    def check(v, field):
        if v is None and null:
            return None
        if not isinstance(v, dict):
            raise _Bad(field, what + (" or null" if null else ""), v)
        out = dict(v)
        for name, (kind, default) in fields.items():
            sub = f"{field}.{name}" if field else name
            if name in v:
                out[name] = kind(v[name], sub)
            elif default is _ABSENT:  # left missing: the window keeps what it shows
                continue
            elif default is dict:  # a missing object: an empty one, its own fields defaulted
                out[name] = kind({}, sub)
            elif default is not _REQUIRED:
                out[name] = default() if callable(default) else default
            else:
                raise _Bad(sub, "present", None)
        return out
    return check


_REQUIRED = object()
_ABSENT = object()


def camera(v, field):
    """Position, focal point and view up: 3 rows of 3 finite numbers, a position off the focal point."""
    if not (isinstance(v, list) and len(v) == 3 and
            all(isinstance(r, list) and len(r) == 3 and all(_number(x) for x in r) for r in v)):
        raise _Bad(field, "3 rows of 3 finite numbers (position, focal point, view up)", v)
    if v[0] == v[1] or not any(v[2]):
        raise _Bad(field, "a camera whose position differs from its focal point and whose view up is not zero", v)
    return v


def cameras(v, field):
    if not isinstance(v, dict) or len(v) > 64:
        raise _Bad(field, "an object of views", v)
    return {k: camera(c, f"{field}.{k}") for k, c in v.items()}


def phone(v, field):
    if not (isinstance(v, list) and len(v) == 3 and _number(v[0]) and _number(v[1]) and isinstance(v[2], str)
            and v[0] <= v[1]):
        raise _Bad(field, "[start, end, label] with start <= end (seconds)", v)
    return v


def word(v, field):
    if not (isinstance(v, list) and len(v) == 3 and _number(v[0]) and _number(v[1]) and isinstance(v[2], str)
            and v[0] <= v[1]):
        raise _Bad(field, "[start s, end s, word] with start <= end (the editor's word tier)", v)
    return v


def field_level(v, field):
    if not (isinstance(v, list) and len(v) == 2 and all(isinstance(x, str) for x in v)):
        raise _Bad(field, "a [field, level] pair", v)
    return v


def palette(v, field):
    """The session palette's record (``{"ranking": {kind: [levels]}}``), or null."""
    if v is None:
        return None
    from app.models.palette import SessionPalette

    try:
        SessionPalette.from_dict(v)
    except ValueError as exc:
        raise _Bad(field, f"a palette record ({exc})", v) from None
    return v


def _session_schema():
    from app.files.source_loading import PRESETS
    from app.models.state import COLOR_MODES, HEMISPHERES, HORIZON_MAX_MS

    index = whole(0, null=True, what="a non-negative integer")
    rate = number(0, 100_000, above=True, what="a frame rate in Hz (above 0, at most 100000)")
    labels = array(text(), what="an array of phone labels")
    return record({
        "source": (record({"path": (text(null=True, what="a file name"), None),
                           "preset": (text(choices=PRESETS, what=f"a preset name ({', '.join(PRESETS)})"),
                                      "default"),
                           "kind": (text(null=True), None)}), lambda: {"path": None, "preset": "default"}),
        "selection": (record({"frame": (index, None), "state": (index, None), "target": (index, None)}), dict),
        "color_mode": (text(choices=COLOR_MODES, what=f"a colour mode ({', '.join(COLOR_MODES)})"), "density"),
        "hemisphere": (text(choices=HEMISPHERES, what=f"a hemisphere ({', '.join(HEMISPHERES)})"), "future"),
        "horizon_ms": (number(0, HORIZON_MAX_MS, null=True, what=f"a number of milliseconds up to {HORIZON_MAX_MS:g}"),
                       None),
        "phone_filter": (labels, list),
        "path_mode": (boolean, False),
        "utterance": (text(null=True, what="an utterance id"), None),
        "visible_phones": (labels, list),
        "component": (whole(0, null=True, what="a component index"), None),
        "hidden_layers": (array(text(), what="an array of layer names"), list),
        "ellipsoid_opacity": (number(0, 1, what="a number from 0 to 1"), _ABSENT),
        "color_field": (text(null=True, what="a field name"), None),
        "field_filter": (array(field_level, what="an array of [field, level] pairs"), list),
        "palette": (palette, None),
        "cameras": (cameras, dict),
        "extra": (record({"editor": (record({"text": (text(null=True), None), "method": (text(null=True), None),
                                             "source": (text(null=True), None), "oracle": (boolean, True),
                                             "words": (array(word, what="an array of [start s, end s, word] (the "
                                                             "editor's word tier)"), list),
                                             "sound": (boolean, True)}), dict),
                      # the signals' own fields are checked by app.models.signals.Signals.from_settings
                      "signals": (record({}, null=True), None),
                      "compare": (record({"field": (text(what="a field name"), _ABSENT),
                                          "levels": (array(text(), what="an array of level names"), _ABSENT),
                                          "paired_by": (text(what="a field name"), _ABSENT),
                                          "n_permutations": (whole(1, what="a whole number of permutations >= 1"),
                                                             _ABSENT)}, null=True), None)}), dict),
        "synthetic": (record({"label": (text(), ""), "rate": (rate, _REQUIRED),
                              "method": (text(null=True), None),
                              "warnings": (array(text(), what="an array of strings"), list)}, null=True), None),
        "targets": (record({"labels": (array(text(), what="an array of target labels"), _REQUIRED),
                            "phones": (array(phone, what="an array of [start, end, label]"), list),
                            "n_frames": (whole(0, MAX_FRAMES), _REQUIRED), "rate": (rate, _REQUIRED),
                            "source": (text(), ""), "utterance": (text(null=True), None)}, null=True), None),
        "arrays": (record({"file": (text(what="a plain .npz file name beside the session"), _REQUIRED),
                           "sha256": (text(pattern=r"[0-9a-f]{64}", what="a SHA-256 in hexadecimal"), _REQUIRED)},
                          null=True), None),
    })


def check_session(d, path) -> dict:
    """``d`` (a session file's parsed JSON) checked field by field; returns it with defaults filled in.

    Raises :class:`SessionError` naming ``path``, the field, what it must be and what it holds.
    """
    try:
        return _session_schema()(d, "")
    except _Bad as bad:
        if bad.field in ("color_mode", "hemisphere") and isinstance(bad.value, str):
            what = "colour mode" if bad.field == "color_mode" else "hemisphere"
            raise SessionError(f"{path}: {what} {bad.value!r} is not {bad.what.split(' (')[1].rstrip(')')}; the "
                               "session file is damaged") from None
        got = json.dumps(bad.value)[:60] if bad.value is not None or bad.what != "present" else "nothing"
        raise SessionError(f"{path}: field {bad.field!r} must be {bad.what}, got {got} ({json_type(bad.value)}); "
                           "the session file is damaged") from None
