"""The explorer's one shared application state, free of Qt and VTK.

Every view observes an :class:`AppState` and changes it through its methods; views
never call each other. Selections are indices (frames, states), never actors. Each
field (:mod:`app.models.state.fields`) has an :class:`~app.models.state.events.Event` in
``state.events`` that fires with the new value when the value changes; the derived data
the views read (:mod:`app.models.state.derived`) are computed once per manifold; how points
are coloured is :mod:`app.models.colouring`.
"""
from __future__ import annotations

import numpy as np

from app.models.state.conditions import ConditionMutators
from app.models.state.derived import DerivedCaches
from app.models.state.events import Batching, Events, batched
from app.models.state.fields import EVENT_FIELDS, FIELD, FIELDS, SETTINGS
from app.models.state.targets import insert_state_target, state_path
from app.models.state.trajectory import original_trajectory

__all__ = ["AppState"]


class AppState(Batching, DerivedCaches, ConditionMutators):
    """What the user has selected and how things are shown; observed by every view.

    Parameters
    ----------
    manifold : engine.manifold.model.Manifold or None
        The fitted manifold the indices refer to.

    Attributes
    ----------
    frame, state, target : int or None
        Selected frame, its state, and the second (target) state of the path.
    path : ndarray of int or None
        Minimum-distance state path from ``state`` to ``target`` (None: none or unreachable).
    hemisphere : {"future", "past", "both", "off"}
        Which hemisphere of the selected state distance colouring shows.
    horizon_ms : float or None
        Time horizon of the hemisphere in ms (None: every reachable state); converted to
        hops at the corpus frame rate (:func:`engine.graph.hemispheres.horizon_hops`).
    color_mode : {"density", "class", "phone", "speaker", "utterance", "distance", "field", "difference"}
    color_field : str or None
        The per-utterance field the "field" colouring and the small multiples show.
    field_filter : frozenset of (str, str)
        ``(field, level)`` pairs shown (empty: every frame); the others are dimmed.
    comparison : app.models.compare_run.ComparisonShown or None
        What the difference colouring shows.
    gestures : engine.recordings.signals.gestures.GestureSet or None
        The gestural landmarks shown (the timeline's tier, the marks in the manifold view).
    phone_filter : frozenset of str
        Phones the phone colouring shows (empty: all phones).
    path_mode : bool
        When True, a click while a state is selected sets the target instead.
    utterance : str or None
    original, synthetic : TrajectoryData or None
    visible_phones : frozenset of str
        Phones whose cluster ellipsoids are shown.
    playback : int or None
        Index into the trajectories being played (None: show the selection).
    playing : bool
        Whether playback runs (the lip view's timer advances ``playback``).
    component : int or None
        Shape component shown as a deformation in the lip view (None: the lip view follows
        the selection; selecting a frame or state, or :meth:`reset_view`, sets None).
    hover : int or None
        Frame under the mouse pointer in the manifold view (readout only; never selects).
    source : dict
        Where the manifold came from (``path``, ``preset``), for sessions.
    """

    _event_fields = EVENT_FIELDS
    _setting_fields = frozenset(SETTINGS)
    _selection_events = frozenset({"frame", "state", "target"})

    def __init__(self, manifold=None):
        self.events = Events(EVENT_FIELDS)
        for f in FIELDS:
            setattr(self, f.name, f.default)
        self.manifold = manifold
        self.source: dict = {"path": None, "preset": "default"}
        self._take_prepared(manifold)
        self._init_batching()
        self.palette = self._palette_for(manifold)

    # ----------------------------------------------------------- manifold
    @batched
    def set_manifold(self, manifold, *, source: dict | None = None) -> None:
        """Replace the manifold; every other field back to its default (:data:`FIELDS`).

        A new file starts from the default view: no selection, colouring or readout of
        the previous one survives, and each field that changes is announced after
        ``manifold`` in the same action.
        """
        if source is not None:
            self.source = dict(source)
        self._take_prepared(manifold)
        self._set("manifold", manifold, announce=True)
        for f in FIELDS:
            if f.name != "manifold":
                self._set(f.name, f.default)
        self._set("palette", self._palette_for(manifold))

    @batched
    def reset_view(self) -> None:
        """Back to the default view of this manifold: every view field of :data:`FIELDS` at its
        default (no selection, path, component or hover, density colouring, future hemisphere,
        default horizon, no phone filter or ellipsoids); the utterance and trajectories stay."""
        for f in FIELDS:
            if f.view:
                self._set(f.name, f.default)

    # ----------------------------------------------------------- settings
    @batched
    def reset_settings(self) -> None:
        """Every view setting (:data:`app.models.state.fields.SETTINGS`: colouring, hemisphere, horizon,
        phone filter, path mode, ellipsoids and their opacity, hidden layers) back to its default, as
        one action (undone as one); the selection stays."""
        for name in SETTINGS:
            self._set(name, FIELD[name].default)

    @batched
    def apply_settings(self, values: dict) -> None:
        """Set the view settings ``values`` (``{name: value}``, e.g. an undo's ``before``) as one action."""
        bad = sorted(set(values) - set(SETTINGS))
        if bad:
            raise KeyError(f"not view settings: {', '.join(bad)}; the settings are {', '.join(SETTINGS)}")
        for name in SETTINGS:  # declaration order: the colour mode after the hemisphere, as the setters do
            if name in values:
                self._set(name, values[name])

    def settings_values(self) -> dict:
        """``{name: value}`` of every view setting."""
        return {name: getattr(self, name) for name in SETTINGS}

    @batched
    def set_ellipsoid_opacity(self, opacity) -> None:
        """How opaque the cluster ellipsoids' fill is, 0 (outline only) to 1."""
        self._set("ellipsoid_opacity", opacity)

    @batched
    def set_layer_visible(self, layer: str, visible: bool) -> None:
        """Show or hide a layer of the manifold view (:data:`app.models.state.fields.LAYERS`)."""
        hidden = set(self.hidden_layers)
        (hidden.discard if visible else hidden.add)(str(layer))
        self._set("hidden_layers", hidden)

    @batched
    def set_hidden_layers(self, layers) -> None:
        """The layers of the manifold view hidden (:data:`app.models.state.fields.LAYERS`)."""
        self._set("hidden_layers", layers)

    @batched
    def set_palette(self, palette) -> None:
        """The session's category colours (a :class:`app.models.palette.SessionPalette`; e.g. from a session)."""
        self._set("palette", palette)

    # ---------------------------------------------------------- selection
    def _check_index(self, value, limit, what):
        """``value`` as an int in ``0..limit - 1`` (None passes); TypeError / IndexError naming ``what``."""
        if value is None:
            return None
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            raise TypeError(f"{what} must be an int index, got {value!r}")
        value = int(value)
        if not 0 <= value < limit:
            raise IndexError(f"{what} {value} out of range 0..{limit - 1}")
        return value

    @batched
    def select_frame(self, i, *, as_target: bool | None = None) -> None:
        """Select frame ``i`` and its state.

        With ``as_target=True`` (or ``as_target=None`` while :attr:`path_mode` is on and a
        state is already selected) the frame's state becomes the path target instead,
        keeping the current selection. ``i=None`` clears the selection.
        """
        if i is None:
            self.clear_selection()
            return
        i = self._checked("frame", i)
        s = int(self.manifold.states_.labels_[i])
        if as_target is None:
            as_target = self.path_mode and self.state is not None
        if as_target and self.state is not None:
            self.set_target(s)
            return
        self._set("frame", i)
        self._set("component", None)  # a click means: show me this frame (the lip view follows clicks again)
        self._set_state(s)

    @batched
    def select_state(self, s, *, as_target: bool = False) -> None:
        """Select state ``s`` directly (no particular frame), or make it the path target."""
        s = self._checked("state", s)
        if as_target and self.state is not None:
            self.set_target(s)
            return
        self._set("frame", None)
        self._set("component", None)
        self._set_state(s)

    def _set_state(self, s) -> None:
        changed = s != self.state
        self._set("state", s)
        if changed or self.target is not None:
            self._set("target", None)
            self._update_path()
        if s is not None and self.hemisphere != "off" and self.color_mode != "distance":
            self.set_color_mode("distance")

    @batched
    def set_target(self, s) -> None:
        """Set the path target state (None clears it) and recompute the path."""
        self._set("target", s)
        self._update_path()

    def selected_state_target(self, targets=None, *, frame=None):
        """``targets`` with a target holding the selected state inserted (see :func:`insert_state_target`).

        Raises ValueError when no state is selected (click a point of the manifold first).
        """
        self._require()
        if self.state is None:
            raise ValueError("no state selected: click a point of the manifold first, then add it as a target")
        return insert_state_target(self.manifold, targets, self.state, frame=frame)

    @batched
    def clear_selection(self) -> None:
        self._set("frame", None)
        self._set("state", None)
        self._set("target", None)
        self._update_path()

    def _update_path(self) -> None:
        new = None
        if self.state is not None and self.target is not None:
            new = state_path(self.manifold, self.state, self.target)
        self._set("path", new)

    # -------------------------------------------------------------- modes
    @batched
    def set_hemisphere(self, mode: str) -> None:
        self._set("hemisphere", mode)
        if mode != "off" and self.state is not None and self.color_mode != "distance":
            self.set_color_mode("distance")

    @batched
    def set_horizon(self, ms) -> None:
        """Time horizon of the hemisphere in milliseconds (None: no horizon, every reachable state)."""
        self._set("horizon_ms", ms)

    @batched
    def set_phone_filter(self, labels) -> None:
        """Phones the phone colouring shows (empty: all); unknown labels are refused with the known ones."""
        self._set("phone_filter", labels)

    @batched
    def set_hover(self, i) -> None:
        """Frame under the mouse pointer (None: none); shown in the readout, never selected."""
        self._set("hover", i)

    @batched
    def set_color_mode(self, mode: str) -> None:
        self._set("color_mode", mode)

    @batched
    def set_path_mode(self, on: bool) -> None:
        self._set("path_mode", on)

    # ----------------------------------------------------- trajectories
    @batched
    def set_utterance(self, uid) -> None:
        """Make ``uid`` the current utterance and its captured trajectory the original."""
        if uid is None:
            self._set("utterance", None)
            self.set_trajectories(original=None, synthetic=None)
            return
        traj = original_trajectory(self._require(), uid)  # raises KeyError with known ids
        self._set("utterance", uid)
        self.set_trajectories(original=traj, synthetic=None)

    @batched
    def set_trajectories(self, *, original=..., synthetic=...) -> None:
        """Set the original and/or synthetic trajectory (omit one to keep it); announced even when unchanged."""
        if original is not ...:
            self._set("original", original)
        if synthetic is not ...:
            self._set("synthetic", synthetic)
        self.set_playing(False)
        self._set("playback", None)
        self._emit("trajectory")

    @property
    def n_playback(self) -> int:
        """Frames of the longer of the original and synthetic trajectories (0: none)."""
        return max([len(t) for t in (self.original, self.synthetic) if t is not None], default=0)

    @batched
    def set_playback(self, k) -> None:
        """Current playback index into the trajectories (None: show the selection). While a range plays
        (:meth:`play`), reaching its stop shows its last frame and stops."""
        stop = self.play_stop
        if self.playing and stop is not None and k is not None and k >= stop - 1:
            self._set("playback", stop - 1)
            self.set_playing(False)
            return
        self._set("playback", k)

    @batched
    def set_playing(self, on: bool) -> None:
        """Start or stop playback (starting with nothing to play is refused quietly); stopping ends a range."""
        self._set("playing", on)
        if not self.playing:
            self._set("play_stop", None)

    @batched
    def play(self, start: int = 0, stop: int | None = None) -> bool:
        """Play frames ``start`` up to (not including) ``stop`` (None: to the end) and stop there, as
        Praat's Tab plays a selection. Returns False (nothing changes) when there is nothing to play."""
        n = self.n_playback
        if n == 0:
            return False
        start = int(min(max(int(start), 0), n - 1))
        stop = None if stop is None else int(min(max(int(stop), start + 1), n))
        with self.batch():
            self.set_playing(False)
            self._set("playback", start)
            self._set("playing", True)
            self._set("play_stop", None if stop is None or stop >= n else stop)
        return True

    # ------------------------------------------------------------ phones
    @batched
    def set_visible_phones(self, labels) -> None:
        self._set("visible_phones", labels)

    @batched
    def set_phone_visible(self, label: str, visible: bool) -> None:
        cur = set(self.visible_phones)
        (cur.add if visible else cur.discard)(str(label))
        self.set_visible_phones(cur)

    @batched
    def set_component(self, index) -> None:
        """Shape component shown as a deformation (None: show the selection instead)."""
        self._set("component", index)

    # -------------------------------------------------------------- util
    def _checked(self, name, value):
        """``value`` as field ``name``'s check accepts it (raises as the check does)."""
        check = FIELD[name].check
        return value if check is None else check(self, value)

    def _set(self, name, value, *, announce=False) -> None:
        """Set field ``name`` through its check; announce it when it changed (or ``announce``)."""
        f = FIELD[name]
        value = self._checked(name, value)
        old = getattr(self, name)
        if announce or not f.same(old, value):
            self._note_before(name, old)
            setattr(self, name, value)
            self._emit(f.event_name)
