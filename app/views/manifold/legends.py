"""The manifold view's legends: what the points' colours mean, and every glyph drawn.

A part of :class:`app.views.manifold_view.ManifoldView` (a mixin). The points' legend
(lower left) lists the categories of the colour mode, or the greys of "no value" beside a
colour bar; the glyph legend (upper left) names each kind of thing drawn now
(:func:`app.models.view_legend.glyph_legend`). Each box is made once per manifold and its
rows changed in place only when they change, without a render of its own (a click adds or
removes no actor); "legend" in the hidden layers hides both.
"""
from __future__ import annotations

from app.models.view_legend import glyph_legend, point_legend
from app.scene import legend as scene_legend

__all__ = ["ManifoldLegends", "ROW_HEIGHT"]

#: a legend row's height as a share of the view's
ROW_HEIGHT = 0.034


class ManifoldLegends:
    """The two legend boxes of :class:`app.views.manifold_view.ManifoldView`."""

    def _forget_legends(self) -> None:
        self.legends: dict = {}  # "points" / "glyphs" -> the vtkLegendBoxActor shown
        self.legend_rows: dict = {"points": (), "glyphs": ()}

    @property
    def legend(self):
        """The points' legend box (None while it shows nothing)."""
        box = self.legends.get("points")
        return box if box is not None and box.GetVisibility() else None

    def _update_legends(self) -> None:
        """Bring both legend boxes up to date with the state and the colouring."""
        if "points" not in self.handles:
            return
        s = self.state
        off = "legend" in s.hidden_layers
        local = bool(self.handles["local"].visible) if "local" in self.handles else False
        rows = {
            "points": () if off or "points" in s.hidden_layers else tuple(point_legend(self.coloring)),
            "glyphs": () if off else tuple(glyph_legend(s, hidden=s.hidden_layers, local_frame=local)),
        }
        where = {"points": "lower left", "glyphs": "upper left"}
        for key, new in rows.items():
            if new == self.legend_rows.get(key) and key in self.legends:
                continue
            width = min(0.34, 0.05 + 0.0085 * max([len(r[0]) for r in new], default=1))
            size = (width, min(0.6, ROW_HEIGHT * len(new) + 0.02))
            if key not in self.legends:
                self.legends[key] = scene_legend.add_legend(self.plotter, list(new), size=size, loc=where[key],
                                                            name=f"{key}-legend")
            else:
                scene_legend.set_entries(self.legends[key], list(new), size=size, loc=where[key])
            self.legend_rows[key] = new
