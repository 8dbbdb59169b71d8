"""The state's events: a minimal signal, and the batching that sends each change once per action (Qt-free)."""
from __future__ import annotations

import functools
from contextlib import contextmanager

__all__ = ["Event", "Events", "Batching", "batched"]


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


class Events:
    """Namespace of a state's events: one :class:`Event` per name of ``names``, and ``changed``.

    ``changed`` fires once per user action with the frozenset of the event names that
    action changed (after every field event of that action), so a view that depends on
    several fields redraws once (see :meth:`Batching.batch`). ``settings`` fires after it, once
    per action that changed a view setting, with ``(before, after)``: dicts of those settings'
    values (what the window's undo stack records).
    """

    def __init__(self, names):
        self.NAMES = tuple(names)
        for n in self.NAMES:
            setattr(self, n, Event(n))
        self.changed = Event("changed")
        self.settings = Event("settings")


def batched(method):
    """Run a public mutator of a :class:`Batching` object as one batch (one ``changed`` emission)."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        with self.batch():
            return method(self, *args, **kwargs)

    return wrapper


class Batching:
    """Holds events while a batch is open and sends each once when the outermost batch ends.

    The owner sets ``events`` (an :class:`Events`), ``_event_fields`` (event name -> the
    attribute names it carries, in order) and ``_setting_fields`` (the fields announced on
    ``events.settings``), calls :meth:`_init_batching`, and :meth:`_note_before` before it
    changes a field.
    """

    _event_fields: dict = {}
    _setting_fields: frozenset = frozenset()
    #: events whose action's setting changes are consequences, not choices (a click that colours by hop
    #: distance): not announced on ``events.settings``
    _selection_events: frozenset = frozenset()

    def _init_batching(self) -> None:
        self._batch_depth = 0
        self._pending: dict = {}  # event name -> None, in order of first change (a batch's events)
        self._before: dict = {}  # setting -> its value before this action first changed it

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

    def _note_before(self, name: str, old) -> None:
        """Remember a setting's value before this action first changes it (for ``events.settings``)."""
        if name in self._setting_fields and name not in self._before:
            self._before[name] = old

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
                    getattr(self.events, name).emit(*(getattr(self, f) for f in self._event_fields[name]))
        finally:
            self._batch_depth -= 1
            self._pending = {}
        before, self._before = self._before, {}
        if changed:
            self.events.changed.emit(frozenset(changed))
        moved = {k: v for k, v in before.items() if not _same(v, getattr(self, k))}
        if moved and "manifold" not in changed and not self._selection_events & set(changed):
            # changed and back is no change; a new manifold starts anew; a click's own colouring is the click's
            self.events.settings.emit(moved, {k: getattr(self, k) for k in moved})


def _same(a, b) -> bool:
    return a is b or (type(a) is type(b) and a == b)
