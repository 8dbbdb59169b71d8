"""The state's mutators for a corpus's conditions: colour and filter by a per-utterance field, the comparison
shown, the gestural landmarks shown (a part of :class:`app.models.state.AppState`, Qt-free).

Fields are read through :func:`app.models.field_colouring.utterance_field_values` (the comparison
engine's one reader of per-utterance metadata); a filter is a frozenset of ``(field, level)``
pairs: a frame is shown when, for every field named, its utterance's level is one of those
given (the other frames are dimmed, as the phone filter dims).
"""
from __future__ import annotations

from app.models.state.events import batched

__all__ = ["ConditionMutators"]


class ConditionMutators:
    """Field colouring, the field filter, the comparison and the gestures of :class:`AppState` (a mixin)."""

    @batched
    def set_color_field(self, name) -> None:
        """The field the "field" colouring and the small multiples show (None: none chosen)."""
        self._set("color_field", name)

    @batched
    def colour_by_field(self, name) -> None:
        """Colour the points by each utterance's level of field ``name``, as one action."""
        self._set("color_field", name)
        self.set_color_mode("field")

    @batched
    def set_field_filter(self, pairs) -> None:
        """The ``(field, level)`` pairs shown (empty: every frame); unknown fields or levels are refused."""
        self._set("field_filter", pairs)

    @batched
    def set_field_levels(self, name: str, levels) -> None:
        """Show only ``levels`` of field ``name`` (empty: every level of it); the other fields' filters stay."""
        keep = {p for p in self.field_filter if p[0] != str(name)}
        self._set("field_filter", keep | {(str(name), str(lv)) for lv in levels})

    def field_levels_shown(self, name: str):
        """The levels of field ``name`` the filter shows (None: no filter on it)."""
        levels = {lv for f, lv in self.field_filter if f == str(name)}
        return levels or None

    @batched
    def set_comparison(self, shown) -> None:
        """The comparison the difference view shows (an :class:`app.models.compare_run.ComparisonShown` or None)."""
        self._set("comparison", shown)

    @batched
    def set_gestures(self, gestures) -> None:
        """The gestural landmarks shown (an :class:`engine.recordings.signals.gestures.GestureSet` or None)."""
        self._set("gestures", gestures)
