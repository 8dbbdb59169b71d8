"""The state's observable fields, declared once: name, default, check, event, and whether Esc resets it.

The constructor of :class:`app.models.state.AppState`, its ``set_manifold``, its view reset
and its events namespace are all read from :data:`FIELDS`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["StateField", "FIELDS", "FIELD", "EVENT_FIELDS", "SETTINGS", "HEMISPHERES", "COLOR_MODES", "LAYERS",
           "DEFAULT_HORIZON_MS", "HORIZON_MAX_MS", "DEFAULT_ELLIPSOID_OPACITY"]

HEMISPHERES = ("future", "past", "both", "off")
#: "field": each utterance's level of :attr:`AppState.color_field`; "difference": the comparison's enrichment
COLOR_MODES = ("density", "class", "phone", "speaker", "utterance", "distance", "field", "difference")
#: layers of the manifold view the user can hide (View menu, the view's boxes)
LAYERS = ("points", "plane", "axes", "legend")
#: how opaque a cluster ellipsoid's fill is when first shown (its outline is always opaque)
DEFAULT_ELLIPSOID_OPACITY = 0.3
#: the hemisphere's time horizon when a manifold is opened (about half the frames inside on the
#: default talker at 60 frames/s); None = no horizon
DEFAULT_HORIZON_MS = 100.0
#: longest horizon the explorer offers (longer ones are "no horizon")
HORIZON_MAX_MS = 1000.0


def _index(what, limit):
    """A check for an int index ``0 <= i < limit(state)`` (None allowed), naming ``what`` when refused."""

    def check(state, value):
        return state._check_index(value, None if value is None else limit(state), what)

    return check


def _one_of(choices, what):
    def check(state, value):
        if value not in choices:
            raise ValueError(f"{what} must be one of {choices}, got {value!r}")
        return value

    return check


def _horizon(state, ms):
    if ms is not None:
        if isinstance(ms, (bool, np.bool_)) or not isinstance(ms, (int, float, np.integer, np.floating)):
            raise TypeError(f"horizon must be a number of milliseconds or None, got {ms!r}")
        ms = float(ms)
        if not (0.0 <= ms <= HORIZON_MAX_MS):
            raise ValueError(f"horizon {ms:g} ms is outside 0..{HORIZON_MAX_MS:g} ms; use None for no horizon")
    return ms


def _labels(state, labels):
    return frozenset(str(x) for x in labels)


def _phone_filter(state, labels):
    labels = _labels(state, labels)
    if labels and state.manifold is not None:
        known = set(state.phone_names)
        bad = sorted(labels - known)
        if bad:
            raise ValueError(f"unknown phone(s) {', '.join(bad)}; this corpus has {', '.join(sorted(known))}")
    return labels


def _field_name(state, name):
    if name is None:
        return None
    name = str(name)
    if state.manifold is not None:
        from app.models.field_colouring import utterance_field_values

        known = utterance_field_values(state)
        if name not in known:
            raise ValueError(f"no field {name!r}; this corpus's utterances have {', '.join(known)}")
    return name


def _field_filter(state, pairs):
    """A frozenset of (field, level) pairs: the levels shown of each field named (empty: every frame)."""
    out = set()
    for pair in pairs:
        if isinstance(pair, str) or len(pair) != 2:
            raise TypeError(f"a field filter holds (field, level) pairs, got {pair!r}")
        out.add((str(pair[0]), str(pair[1])))
    if out and state.manifold is not None:
        from app.models.field_colouring import utterance_field_values

        known = utterance_field_values(state)
        for name, level in sorted(out):
            if name not in known:
                raise ValueError(f"no field {name!r}; this corpus's utterances have {', '.join(known)}")
            if level not in set(known[name].tolist()):
                levels = sorted(set(known[name].tolist()) - {""})
                raise ValueError(f"field {name!r} has no level {level!r}; its levels are {', '.join(levels[:20])}")
    return frozenset(out)


def _play_stop(state, k):
    if k is None:
        return None
    return state._check_index(k, state.n_playback + 1, "playback stop") or None  # 0: no stop


def _opacity(state, v):
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise TypeError(f"ellipsoid opacity must be a number from 0 to 1, got {v!r}")
    v = float(v)
    if not 0.0 <= v <= 1.0:
        raise ValueError(f"ellipsoid opacity {v:g} is outside 0..1 (0: outline only, 1: opaque)")
    return v


def _layers(state, names):
    names = frozenset(str(x) for x in names)
    bad = sorted(names - set(LAYERS))
    if bad:
        raise ValueError(f"unknown layer(s) {', '.join(bad)}; the manifold view has {', '.join(LAYERS)}")
    return names


def _palette(state, palette):
    from app.models.palette import SessionPalette

    if palette is not None and not isinstance(palette, SessionPalette):
        raise TypeError(f"palette must be a SessionPalette or None, got {type(palette).__name__}")
    return palette


def _playback(state, k):
    if k is not None and state.n_playback == 0:
        raise RuntimeError("nothing to play: choose an utterance or synthesise a trajectory first")
    return state._check_index(k, None if k is None else state.n_playback, "playback frame")


def _same_value(old, new) -> bool:
    return old is new or (type(old) is type(new) and old == new)


def _same_path(old, new) -> bool:
    return (old is None) == (new is None) and (old is None or np.array_equal(old, new))


def _same_object(old, new) -> bool:
    return old is new


@dataclass(frozen=True)
class StateField:
    """One observable field of :class:`app.models.state.AppState`, declared once.

    Parameters
    ----------
    name : str
    default : object
        The value of a new state, and after :meth:`AppState.set_manifold` (immutable).
    check : callable(state, value) -> value, optional
        Validates a new value and returns what is stored (raises with the value and the limit).
    event : str, optional
        Event announcing a change (default: ``name``); fields sharing one event are emitted
        together, in declaration order (``trajectory``: original, synthetic).
    view : bool
        Part of the view :meth:`AppState.reset_view` returns to its default.
    setting : bool
        A view setting the user chose (colouring, horizon, filter, ellipsoids, layers): its
        changes are announced on ``events.settings`` (undo, redo), saved in sessions, and
        :meth:`AppState.reset_settings` returns it to its default. Esc never touches it.
    same : callable(old, new) -> bool
        When a new value is no change (nothing is announced).
    """

    name: str
    default: object = None
    check: object = None
    event: str = ""
    view: bool = False
    same: object = _same_value
    setting: bool = False

    @property
    def event_name(self) -> str:
        return self.event or self.name


#: every observable field of the state: the one place its name, default and check are given
FIELDS = (
    StateField("manifold", same=_same_object),
    StateField("frame", check=_index("frame", lambda s: s.n_frames), view=True),
    StateField("state", check=_index("state", lambda s: s.n_states), view=True),
    StateField("target", check=_index("target state", lambda s: s.n_states), view=True),
    StateField("path", view=True, same=_same_path),
    StateField("hemisphere", "future", _one_of(HEMISPHERES, "hemisphere"), view=True, setting=True),
    StateField("horizon_ms", DEFAULT_HORIZON_MS, _horizon, view=True, setting=True),
    StateField("color_mode", "density", _one_of(COLOR_MODES, "colour mode"), view=True, setting=True),
    StateField("phone_filter", frozenset(), _phone_filter, view=True, setting=True),
    StateField("path_mode", False, lambda s, on: bool(on), view=True, setting=True),
    StateField("utterance"),
    StateField("original", event="trajectory", same=_same_object),
    StateField("synthetic", event="trajectory", same=_same_object),
    StateField("visible_phones", frozenset(), _labels, view=True, setting=True),
    StateField("ellipsoid_opacity", DEFAULT_ELLIPSOID_OPACITY, _opacity, view=True, setting=True),
    StateField("hidden_layers", frozenset(), _layers, view=True, setting=True),
    StateField("color_field", check=_field_name, view=True, setting=True),
    StateField("field_filter", frozenset(), _field_filter, view=True, setting=True),
    StateField("comparison", same=_same_object),
    StateField("gestures", same=_same_object),
    StateField("palette", check=_palette, same=_same_object),
    StateField("playback", check=_playback),
    StateField("playing", False, lambda s, on: bool(on) and s.n_playback > 0),
    StateField("play_stop", check=_play_stop),
    StateField("component", check=_index("shape component", lambda s: int(s._require().shape_.n_components_)),
               view=True),
    StateField("hover", check=_index("hovered frame", lambda s: s.n_frames), view=True),
)
#: field name -> its StateField
FIELD = {f.name: f for f in FIELDS}
#: the names of the view settings (:attr:`StateField.setting`), in declaration order
SETTINGS = tuple(f.name for f in FIELDS if f.setting)
#: event name -> the fields it announces, in declaration order
EVENT_FIELDS: dict = {}
for _f in FIELDS:
    EVENT_FIELDS.setdefault(_f.event_name, []).append(_f.name)
del _f
