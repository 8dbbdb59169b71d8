"""The manifold view's colour choices and its filter by per-utterance fields (a mixin of the view).

The colour box lists the fixed modes, then one entry per per-utterance field of the corpus
("Field: emotion", "Field: sex", ...: :func:`app.models.field_colouring.colour_fields`), then the
comparison's "Difference"; choosing a field colours by it in one action (undone as one). The
**Filter** button's menu has a submenu per field (speaker too) whose ticked levels are shown,
the others dimmed; "Show every level" clears the filter. Both write the state and follow it.
"""
from __future__ import annotations

from PySide6 import QtWidgets

from app.models.state.fields import COLOR_MODES
from app.views._common import blocked

__all__ = ["FieldControls", "COLOR_LABELS", "FILTER_MENU_MAX"]

COLOR_LABELS = {"density": "Density", "class": "Tangent class", "phone": "Phone", "speaker": "Speaker",
                "utterance": "Utterance", "distance": "Hop distance", "difference": "Difference"}
#: levels a field's filter submenu lists (a field with more is filtered from the first ones only)
FILTER_MENU_MAX = 40


class FieldControls:
    """Colour by and filter by a field, of :class:`app.views.manifold_view.ManifoldView`."""

    def _make_field_controls(self) -> None:
        self.color_box = QtWidgets.QComboBox()
        self.color_box.setToolTip("Colour the points by: density, tangent class, phone, speaker, utterance, hop "
                                  "distance, a per-utterance field (emotion, sex, text ...), or the difference "
                                  "between two levels (Compare panel)")
        self.color_box.setSizeAdjustPolicy(QtWidgets.QComboBox.SizeAdjustPolicy.AdjustToContents)
        self._fill_colour_box()
        self.filter_btn = QtWidgets.QToolButton()
        self.filter_btn.setText("Filter")
        self.filter_btn.setToolTip("Show only some levels of a per-utterance field (speaker, emotion, text ...); "
                                   "the other frames are dimmed")
        self.filter_btn.setPopupMode(QtWidgets.QToolButton.ToolButtonPopupMode.InstantPopup)
        self.filter_menu = QtWidgets.QMenu(self.filter_btn)
        self.filter_menu.aboutToShow.connect(self._fill_filter_menu)
        self.filter_btn.setMenu(self.filter_menu)
        self.color_box.currentIndexChanged.connect(lambda _i: self._colour_chosen())

    def _fields(self) -> list[str]:
        from app.models.field_colouring import colour_fields

        return colour_fields(self.state) if self.state.manifold is not None else []

    def _fill_colour_box(self) -> None:
        with blocked(self.color_box):
            self.color_box.clear()
            for m in COLOR_MODES:
                if m == "field":
                    for name in self._fields():
                        self.color_box.addItem(f"Field: {name}", f"field:{name}")
                else:
                    self.color_box.addItem(COLOR_LABELS[m], m)
        self._sync_colour_box()

    def _colour_chosen(self) -> None:
        data = self.color_box.currentData()
        if data is None:
            return
        if data.startswith("field:"):
            self.state.colour_by_field(data[len("field:"):])
        else:
            self.state.set_color_mode(data)

    def _sync_colour_box(self) -> None:
        s = self.state
        data = f"field:{s.color_field}" if s.color_mode == "field" else s.color_mode
        with blocked(self.color_box):
            self.color_box.setCurrentIndex(self.color_box.findData(data))

    # ------------------------------------------------------------------ filter
    def _fill_filter_menu(self) -> None:
        from app.models.field_colouring import field_levels, utterance_field_values

        menu, s = self.filter_menu, self.state
        menu.clear()
        if s.manifold is None:
            menu.addAction("(no corpus)").setEnabled(False)
            return
        clear = menu.addAction("Show every level", lambda: s.set_field_filter(()))
        clear.setEnabled(bool(s.field_filter))
        menu.addSeparator()
        for name, _values in utterance_field_values(s).items():
            levels = field_levels(s, name)
            if not levels:
                continue
            shown = s.field_levels_shown(name)
            sub = menu.addMenu(f"{name} ({len(levels)} level{'s' * (len(levels) != 1)})"
                               + (f": {len(shown)} shown" if shown else ""))
            sub.addAction("All levels", lambda n=name: s.set_field_levels(n, ()))
            sub.addSeparator()
            for lv in levels[:FILTER_MENU_MAX]:
                a = sub.addAction(lv)
                a.setCheckable(True)
                a.setChecked(bool(shown) and lv in shown)
                a.toggled.connect(lambda on, n=name, lv=lv: self._toggle_level(n, lv, on))
            if len(levels) > FILTER_MENU_MAX:
                sub.addAction(f"… {len(levels) - FILTER_MENU_MAX} more levels").setEnabled(False)

    def _toggle_level(self, name: str, level: str, on: bool) -> None:
        shown = set(self.state.field_levels_shown(name) or ())
        (shown.add if on else shown.discard)(level)
        self.state.set_field_levels(name, shown)

    def _sync_filter_btn(self) -> None:
        n = len({f for f, _ in self.state.field_filter})
        self.filter_btn.setText("Filter" if not n else f"Filter ({n})")
        self.filter_btn.setToolTip("Shown: " + "; ".join(f"{f} = {lv}" for f, lv in sorted(self.state.field_filter))
                                   if n else "Show only some levels of a per-utterance field (speaker, emotion, text "
                                   "...); the other frames are dimmed")
