"""The explorer's one shared application state, free of Qt and VTK.

Every view observes an :class:`AppState` and changes it through its methods; views
never call each other. Selections are indices (frames, states), never actors. Each
field has an :class:`Event` in ``state.events`` that fires with the new value when
the value changes. Derived data (density, phones, the minimum-distance path) are
pure functions of the manifold and the state, below; how points are coloured is
:mod:`app.models.colouring`.
"""
from __future__ import annotations

import functools
import weakref
from contextlib import contextmanager
from dataclasses import dataclass, field, replace

import numpy as np

__all__ = ["Event", "AppState", "StateField", "FIELDS", "TrajectoryData", "HEMISPHERES", "COLOR_MODES", "DEFAULT_HORIZON_MS",
           "HORIZON_MAX_MS", "knn_density", "frame_phones", "frame_phone_codes", "state_path", "cluster_table",
           "original_trajectory", "prepare_derived", "insert_state_target", "TARGET_SPACING"]

HEMISPHERES = ("future", "past", "both", "off")
COLOR_MODES = ("density", "class", "phone", "utterance", "distance")
#: the hemisphere's time horizon when a manifold is opened (about half the frames inside on the
#: default talker at 60 frames/s); None = no horizon
DEFAULT_HORIZON_MS = 100.0
#: longest horizon the explorer offers (longer ones are "no horizon")
HORIZON_MAX_MS = 1000.0

#: seconds between an appended clicked-state target and the last target (as ``synthesize --spacing``)
TARGET_SPACING = 0.2


class Event:
    """A minimal signal: ``connect(callback)``, ``disconnect(callback)``, ``emit(*args)``.

    Callbacks run in connection order. An exception raised by a callback propagates
    out of :meth:`emit` (nothing is swallowed), so a broken view fails loudly.
    """

    def __init__(self, name: str = ""):
        self.name = name
        self._callbacks: list = []

    def connect(self, callback):
        """Call ``callback(*args)`` on every emit; returns ``callback`` (usable as a decorator)."""
        if not callable(callback):
            raise TypeError(f"event {self.name!r}: connect expects a callable, got {callback!r}")
        if callback not in self._callbacks:
            self._callbacks.append(callback)
        return callback

    def disconnect(self, callback) -> None:
        """Stop calling ``callback``; raises ValueError if it was not connected."""
        try:
            self._callbacks.remove(callback)
        except ValueError:
            raise ValueError(f"event {self.name!r}: {callback!r} is not connected") from None

    def emit(self, *args) -> None:
        for cb in list(self._callbacks):
            cb(*args)

    def __len__(self) -> int:
        return len(self._callbacks)


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
    """One observable field of :class:`AppState`, declared once.

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
        Part of the view :meth:`AppState.reset_view` (Esc) returns to its default.
    same : callable(old, new) -> bool
        When a new value is no change (nothing is announced).
    """

    name: str
    default: object = None
    check: object = None
    event: str = ""
    view: bool = False
    same: object = _same_value

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
    StateField("hemisphere", "future", _one_of(HEMISPHERES, "hemisphere"), view=True),
    StateField("horizon_ms", DEFAULT_HORIZON_MS, _horizon, view=True),
    StateField("color_mode", "density", _one_of(COLOR_MODES, "colour mode"), view=True),
    StateField("phone_filter", frozenset(), _phone_filter, view=True),
    StateField("path_mode", False, lambda s, on: bool(on), view=True),
    StateField("utterance"),
    StateField("original", event="trajectory", same=_same_object),
    StateField("synthetic", event="trajectory", same=_same_object),
    StateField("visible_phones", frozenset(), _labels, view=True),
    StateField("playback", check=_playback),
    StateField("playing", False, lambda s, on: bool(on) and s.n_playback > 0),
    StateField("component", check=_index("shape component", lambda s: int(s._require().shape_.n_components_)),
               view=True),
    StateField("hover", check=_index("hovered frame", lambda s: s.n_frames), view=True),
)
_FIELD = {f.name: f for f in FIELDS}
#: event name -> the fields it announces, in declaration order
_EVENT_FIELDS: dict = {}
for _f in FIELDS:
    _EVENT_FIELDS.setdefault(_f.event_name, []).append(_f.name)
del _f


class _Events:
    """Namespace of the state's events: one per observable field (:data:`FIELDS`), and ``changed``.

    ``changed`` fires once per user action with the frozenset of the event names that
    action changed (after every field event of that action), so a view that depends on
    several fields redraws once (see :meth:`AppState.batch`).
    """

    NAMES = tuple(_EVENT_FIELDS)

    def __init__(self):
        for n in self.NAMES:
            setattr(self, n, Event(n))
        self.changed = Event("changed")


def _batched(method):
    """Run a public mutator of :class:`AppState` as one batch (one ``changed`` emission)."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        with self.batch():
            return method(self, *args, **kwargs)

    return wrapper


@dataclass(frozen=True)
class TrajectoryData:
    """A lip trajectory in the embedding and in the shape space.

    Parameters
    ----------
    Y : ndarray of shape (n, k)
        Positions in F^y (the first 3 columns are drawn).
    Fx : ndarray of shape (n, m) or None
        Shape coordinates, for the lip view (None: not available).
    frames : ndarray of shape (n,) int or None
        Corpus frame indices, for an original (captured) trajectory.
    label : str
        Utterance id or synthesis method.
    rate : float
        Frames per second.
    """

    Y: np.ndarray
    Fx: np.ndarray | None = None
    frames: np.ndarray | None = None
    label: str = ""
    rate: float = 60.0
    extra: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return int(np.asarray(self.Y).shape[0])


def original_trajectory(manifold, uid: str) -> TrajectoryData:
    """The captured trajectory of utterance ``uid``: its rows of F^y and F^x."""
    c = manifold.corpus_
    u = c.utterance(uid)
    idx = np.arange(u.start, u.stop)
    return TrajectoryData(Y=manifold.Fy_[idx], Fx=manifold.Fx_[idx], frames=idx, label=u.id, rate=c.rate)


#: derived data computed ahead of time per manifold object (see prepare_derived)
_PREPARED: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def prepare_derived(manifold, progress=None) -> None:
    """Compute what the views derive from ``manifold`` ahead of showing it (Qt-free, any thread).

    The level of detail of the drawn cloud (:func:`app.models.lod.cloud_detail`: every frame up to
    ``app.models.lod.DEFAULT_MAX_POINTS``, groups of frames above), the k-NN density of every frame (only while every frame
    is drawn: a grouped cloud carries its own density), the phone of every frame, the phone
    clusters and the state graph's cached forms for hemisphere and path queries are
    computed here, e.g. in the loading worker, and picked up by :meth:`AppState.set_manifold`,
    so that showing a manifold does not freeze the window. Reports stage ``"preparing the views"``.
    A corpus whose phone clusters cannot be fitted is left for the clusters panel to
    report, as without this step.
    """
    from app.models.lod import cloud_detail
    from engine.progress import report

    stage = "preparing the views"
    report(progress, stage, 0, 4)
    out = {"cloud": cloud_detail(manifold.Fy_, manifold.states_.labels_)}
    report(progress, stage, 1, 4)
    if out["cloud"].whole:
        out["density"] = knn_density(manifold.Fy_)
    manifold.states_.prepare_queries()  # the state graph's csr forms, so the first click's hemisphere does not build them
    report(progress, stage, 2, 4)
    out["phone_codes"] = frame_phone_codes(manifold.corpus_)
    report(progress, stage, 3, 4)
    try:
        from engine.manifold.clusters import clusters_of

        # phone mid-points, or the kinematic landmarks of a corpus without phone labels
        out["clusters"], out["cluster_kind"], out["cluster_note"] = clusters_of(manifold)
    except ValueError:
        pass  # the panel computes (and reports) it when shown
    report(progress, stage, 4, 4)
    _PREPARED[manifold] = out


class AppState:
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
    color_mode : {"density", "class", "phone", "utterance", "distance"}
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

    def __init__(self, manifold=None):
        self.events = _Events()
        for f in FIELDS:
            setattr(self, f.name, f.default)
        self.manifold = manifold
        self.source: dict = {"path": None, "preset": "default"}
        self._take_prepared(manifold)
        self._batch_depth = 0
        self._pending: dict = {}  # event name -> None, in order of first change (a batch's events)

    # ------------------------------------------------------------- events
    @contextmanager
    def batch(self):
        """Group changes into one action: events are held and sent once when the outermost batch ends.

        Inside ``with state.batch():`` each changed field's event fires once (with its final
        value, in order of first change) when the block ends, then ``events.changed`` fires
        once with the names of every changed field. Every public mutator runs as a batch,
        so one click (frame, state, target, path, colour mode) reaches each view as one
        ``changed`` event. Batches nest; events are flushed even when the block raises.
        """
        self._batch_depth += 1
        try:
            yield self
        finally:
            self._batch_depth -= 1
            if self._batch_depth == 0:
                self._flush()

    def _emit(self, name: str) -> None:
        """Announce event ``name`` (held while a batch is open): the one path of every change."""
        self._pending.setdefault(name, None)
        if self._batch_depth == 0:
            self._flush()

    def _flush(self) -> None:
        changed: dict = {}
        self._batch_depth += 1  # changes made by observers join this flush
        try:
            while self._pending:
                names, self._pending = list(self._pending), {}
                for name in names:
                    changed.setdefault(name, None)
                    getattr(self.events, name).emit(*(getattr(self, f) for f in _EVENT_FIELDS[name]))
        finally:
            self._batch_depth -= 1
            self._pending = {}
        if changed:
            self.events.changed.emit(frozenset(changed))

    # ----------------------------------------------------------- manifold
    @_batched
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

    @_batched
    def reset_view(self) -> None:
        """Back to the default view of this manifold (Esc): every view field of :data:`FIELDS` at its
        default (no selection, path, component or hover, density colouring, future hemisphere,
        default horizon, no phone filter or ellipsoids); the utterance and trajectories stay."""
        for f in FIELDS:
            if f.view:
                self._set(f.name, f.default)

    def _take_prepared(self, manifold) -> None:
        """Pick up what :func:`prepare_derived` computed for ``manifold`` (the rest is computed on demand)."""
        pre = _PREPARED.get(manifold, {}) if manifold is not None else {}
        self._density, self._phone_codes, self._clusters, self._cloud = (
            pre.get(k) for k in ("density", "phone_codes", "clusters", "cloud"))
        self._cluster_kind, self._cluster_note = pre.get("cluster_kind"), pre.get("cluster_note")
        self._phones = None
        self._derived: dict = {}  # per-manifold values of the views, computed once (see derived)
        self._utt_starts = None

    def _require(self):
        if self.manifold is None:
            raise RuntimeError("no manifold is loaded; open a corpus or manifold first")
        return self.manifold

    @property
    def n_frames(self) -> int:
        return int(self._require().Fy_.shape[0])

    @property
    def n_states(self) -> int:
        return int(self._require().states_.centroids_.shape[0])

    @property
    def density(self) -> np.ndarray:
        """k-NN log density of every frame in F^y, computed once per manifold."""
        if self._density is None:
            self._density = knn_density(self._require().Fy_)
        return self._density

    @property
    def cloud(self):
        """The level of detail the manifold view draws (:class:`app.models.lod.CloudDetail`), once per manifold."""
        if self._cloud is None:
            from app.models.lod import cloud_detail

            m = self._require()
            self._cloud = cloud_detail(m.Fy_, m.states_.labels_)
        return self._cloud

    @property
    def phone_codes(self) -> np.ndarray:
        """(N,) int32: every frame's phone as an index into :attr:`phone_names` (``len(phone_names)``:
        no phone), computed once per manifold."""
        if self._phone_codes is None:
            self._phone_codes = frame_phone_codes(self._require().corpus_)
        return self._phone_codes[0]

    @property
    def phone_names(self) -> list[str]:
        """The phone labels covering at least one frame, sorted."""
        self.phone_codes
        return self._phone_codes[1]

    @property
    def phones(self) -> np.ndarray:
        """Phone label of every frame ('' outside phones), computed once per manifold."""
        if self._phones is None:
            self._phones = np.array(list(self.phone_names) + [""])[self.phone_codes]
        return self._phones

    def phone_of(self, i: int) -> str:
        """Frame ``i``'s phone ('' outside phones)."""
        c = int(self.phone_codes[int(i)])
        names = self.phone_names
        return names[c] if c < len(names) else ""

    def utterance_of(self, i: int):
        """The utterance (:class:`engine.recordings.corpus.Utterance`) frame ``i`` belongs to."""
        c = self._require().corpus_
        if self._utt_starts is None:
            self._utt_starts = np.array([u.start for u in c.utterances], dtype=np.int64)
        return c.utterances[int(np.searchsorted(self._utt_starts, int(i), side="right")) - 1]

    def derived(self, key, compute):
        """``compute()`` once per manifold under ``key`` (the views' per-manifold tables, e.g. a colouring's)."""
        if key not in self._derived:
            self._derived[key] = compute()
        return self._derived[key]

    @property
    def clusters(self):
        """The manifold's :class:`engine.manifold.clusters.PhoneClusters`, fitted once per manifold: of its phone
        mid-points, or of its kinematic landmarks when the corpus has no phone labels
        (:func:`engine.manifold.clusters.clusters_of`; :attr:`cluster_kind` says which)."""
        if self._clusters is None:
            from engine.manifold.clusters import clusters_of

            self._clusters, self._cluster_kind, self._cluster_note = clusters_of(self._require())
        return self._clusters

    @property
    def cluster_kind(self) -> str:
        """What the clusters are of: ``"phones"`` or ``"kinematic"`` (landmarks)."""
        self.clusters
        return self._cluster_kind

    @property
    def cluster_note(self) -> str | None:
        """For landmark clusters, the sentence saying what the labels are (None for phones)."""
        self.clusters
        return self._cluster_note

    def cluster_rows(self) -> list[dict]:
        """The phone table of the clusters panel (see :func:`cluster_table`)."""
        return cluster_table(self.clusters)

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

    @_batched
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

    @_batched
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

    @_batched
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

    @_batched
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
    @_batched
    def set_hemisphere(self, mode: str) -> None:
        self._set("hemisphere", mode)
        if mode != "off" and self.state is not None and self.color_mode != "distance":
            self.set_color_mode("distance")

    @_batched
    def set_horizon(self, ms) -> None:
        """Time horizon of the hemisphere in milliseconds (None: no horizon, every reachable state)."""
        self._set("horizon_ms", ms)

    @_batched
    def set_phone_filter(self, labels) -> None:
        """Phones the phone colouring shows (empty: all); unknown labels are refused with the known ones."""
        self._set("phone_filter", labels)

    @_batched
    def set_hover(self, i) -> None:
        """Frame under the mouse pointer (None: none); shown in the readout, never selected."""
        self._set("hover", i)

    @_batched
    def set_color_mode(self, mode: str) -> None:
        self._set("color_mode", mode)

    @_batched
    def set_path_mode(self, on: bool) -> None:
        self._set("path_mode", on)

    # ----------------------------------------------------- trajectories
    @_batched
    def set_utterance(self, uid) -> None:
        """Make ``uid`` the current utterance and its captured trajectory the original."""
        if uid is None:
            self._set("utterance", None)
            self.set_trajectories(original=None, synthetic=None)
            return
        traj = original_trajectory(self._require(), uid)  # raises KeyError with known ids
        self._set("utterance", uid)
        self.set_trajectories(original=traj, synthetic=None)

    @_batched
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

    @_batched
    def set_playback(self, k) -> None:
        """Current playback index into the trajectories (None: show the selection)."""
        self._set("playback", k)

    @_batched
    def set_playing(self, on: bool) -> None:
        """Start or stop playback (starting with nothing to play is refused quietly)."""
        self._set("playing", on)

    # ------------------------------------------------------------ phones
    @_batched
    def set_visible_phones(self, labels) -> None:
        self._set("visible_phones", labels)

    @_batched
    def set_phone_visible(self, label: str, visible: bool) -> None:
        cur = set(self.visible_phones)
        (cur.add if visible else cur.discard)(str(label))
        self.set_visible_phones(cur)

    @_batched
    def set_component(self, index) -> None:
        """Shape component shown as a deformation (None: show the selection instead)."""
        self._set("component", index)

    # -------------------------------------------------------------- util
    def _checked(self, name, value):
        """``value`` as field ``name``'s check accepts it (raises as the check does)."""
        check = _FIELD[name].check
        return value if check is None else check(self, value)

    def _set(self, name, value, *, announce=False) -> None:
        """Set field ``name`` through its check; announce it when it changed (or ``announce``)."""
        f = _FIELD[name]
        value = self._checked(name, value)
        if announce or not f.same(getattr(self, name), value):
            setattr(self, name, value)
            self._emit(f.event_name)


# ======================================================================== derived data
def knn_density(Y, k: int = 10, n_dims: int = 3) -> np.ndarray:
    """Log k-nearest-neighbour density of each point in the first ``n_dims`` dims of ``Y``.

    ``log(k / (N * V_d * r_k^d))`` with r_k the distance to the k-th neighbour.

    Parameters
    ----------
    Y : ndarray of shape (N, >=n_dims)
    k : int, default=10

    Returns
    -------
    ndarray of shape (N,) float32
    """
    from scipy.spatial import cKDTree
    from scipy.special import gammaln

    Y = np.asarray(Y, dtype=np.float64)[:, :n_dims]
    N, d = Y.shape
    if N < 2:
        return np.zeros(N, dtype=np.float32)
    k = int(min(max(k, 1), N - 1))
    r, _ = cKDTree(Y).query(Y, k=k + 1)
    rk = np.maximum(r[:, -1], np.finfo(np.float64).tiny ** (1.0 / d))
    log_vd = (d / 2) * np.log(np.pi) - gammaln(d / 2 + 1)
    return (np.log(k / N) - log_vd - d * np.log(rk)).astype(np.float32)


def frame_phones(corpus) -> np.ndarray:
    """Phone label of every corpus frame; '' where no phone covers it.

    Returns ndarray of shape (N,) of str.
    """
    codes, names = frame_phone_codes(corpus)
    return np.array(list(names) + [""])[codes]


def frame_phone_codes(corpus) -> tuple[np.ndarray, list[str]]:
    """Every corpus frame's phone as a code: ``(codes (N,) int32, names)``.

    A phone covers its frames from the one nearest its start up to (not including) the
    one nearest its end, and at least its first frame; where two cover a frame the later
    phone wins. ``names`` are the labels that cover a frame, sorted; ``codes[i]`` indexes
    them, ``len(names)`` where no phone covers frame i. Vectorised over the phones (no
    loop over frames or phones in Python).
    """
    from engine.recordings.corpus import label_codes

    N = corpus.n_frames
    _mid, labs, _utt, a, b = corpus.phone_table()
    labels, inv = label_codes(labs)  # np.unique's result, without sorting a million strings
    e = np.maximum(b, a + 1)
    codes = np.full(N, len(labels), np.int64)
    if len(a) and np.all(a[1:] >= a[:-1]):  # phones in corpus order (as Corpus.validate keeps them)
        f = np.arange(N)
        j = np.searchsorted(a, f, side="right") - 1  # the last phone starting at or before each frame
        reach = np.maximum.accumulate(e)  # the furthest end of any phone so far
        pending = np.flatnonzero(j >= 0)
        while pending.size:  # the latest phone covering each frame: walk back while one could
            jj = j[pending]
            hit = e[jj] > pending
            codes[pending[hit]] = inv[jj[hit]]
            more = ~hit & (jj > 0)
            more[more] = reach[jj[more] - 1] > pending[more]
            pending = pending[more]
            j[pending] -= 1
    else:
        for k in range(len(a)):
            codes[a[k]:e[k]] = inv[k]
    used = np.bincount(codes, minlength=len(labels) + 1)[:len(labels)] > 0
    remap = np.full(len(labels) + 1, int(used.sum()), np.int64)
    remap[np.flatnonzero(used)] = np.arange(int(used.sum()))
    return remap[codes].astype(np.int32), [str(x) for x in labels[used]]


def cluster_table(clusters) -> list[dict]:
    """Rows of the phone table from fitted PhoneClusters, most frequent phone first.

    Keys as :meth:`engine.manifold.clusters.PhoneClusters.table`: phone, count, opening_fraction,
    lipreading_class, nearest_y, separation_y, separation_x (Bhattacharyya distances), ...
    """
    return sorted(clusters.table(), key=lambda r: (-r["count"], r["phone"]))


def state_path(manifold, a: int, b: int):
    """Minimum-distance state path a -> b (ndarray of int), or None when b is unreachable."""
    from engine.graph.states import UnreachableError

    try:
        return np.asarray(manifold.states_.min_path(int(a), int(b)), dtype=np.int64)
    except UnreachableError:
        return None


def insert_state_target(manifold, targets, state: int, *, frame=None, spacing: float = TARGET_SPACING):
    """A copy of ``targets`` (a TargetSequence, or None) with a target holding ``state`` inserted.

    The target goes at ``frame`` (replacing a target already there), or, with
    ``frame=None``, ``spacing`` seconds after the last target (frame 0 when there are
    none). The trajectory is lengthened to reach the new target. The target carries the
    state (which :class:`engine.synthesis.viterbi.ManifoldSynthesizer` passes through) and the
    state's X (the manifold's map of its centroid, ``state_x_``, else the mean F^x of its
    frames), so the methods that interpolate in X pass through it too. Its label is "".
    """
    from engine.phonetics.targets import Target, TargetError, TargetSequence

    K = int(manifold.states_.centroids_.shape[0])
    s = int(state)
    if not 0 <= s < K:
        raise TargetError(f"state {s} is outside the state graph's 0..{K - 1}")
    rate = float(targets.rate if targets is not None else manifold.corpus_.rate)
    old = list(targets.targets) if targets is not None else []
    if frame is None:
        frame = old[-1].frame + max(1, int(round(spacing * rate))) if old else 0
    frame = int(frame)
    if frame < 0:
        raise TargetError(f"target frame {frame} is negative")
    table = getattr(manifold, "state_x_", None)  # (not computed here: a click must not wait for it)
    if table is not None and table.shape[0] == K:
        x = np.asarray(table[s], dtype=np.float64)
    else:
        x = np.asarray(manifold.Fx_)[np.asarray(manifold.states_.labels_) == s].mean(axis=0, dtype=np.float64)
    new = Target(frame, "", s, None, x)
    ts = sorted([t for t in old if t.frame != frame] + [new], key=lambda t: t.frame)
    n = max(targets.n_frames if targets is not None else 1, frame + 1)
    if targets is None:
        return TargetSequence(tuple(ts), (), n, rate, "clicked states")
    return replace(targets, targets=tuple(ts), n_frames=n)
