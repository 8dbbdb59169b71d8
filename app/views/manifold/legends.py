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

__all__ = ["ManifoldLegends", "ROW_PX"]

#: a legend row's height in pixels (the box is sized to it at every size of the view, so its text keeps one size)
ROW_PX = 15


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
            "glyphs": () if off else tuple(glyph_legend(s, hidden=s.hidden_layers, local_frame=local,
                                                        landmarks=self.landmark_rows())),
        }
        where = {"points": "lower left", "glyphs": "upper left"}
        W, H = (max(int(v), 1) for v in self.plotter.renderer.GetSize())
        sized = (W, H) == getattr(self, "_legend_size", None)
        self._legend_size = (W, H)
        for key, new in rows.items():
            if new == self.legend_rows.get(key) and key in self.legends and sized:
                continue
            chars = max([len(r[0]) for r in new], default=1)
            size = (min(0.45, (28 + 6.2 * chars) / W), min(0.6, (ROW_PX * len(new) + 6) / H))
            if key not in self.legends:
                self.legends[key] = scene_legend.add_legend(self.plotter, list(new), size=size, loc=where[key],
                                                            name=f"{key}-legend")
            else:
                scene_legend.set_entries(self.legends[key], list(new), size=size, loc=where[key])
            self.legend_rows[key] = new
