"""Small multiples: one manifold view per level of a per-utterance field, side by side, linked.

Each view draws only the frames of its level's utterances (at most :data:`MAX_POINTS` of them,
evenly taken), coloured as the manifold view colours them now (density, hop distance within the
horizon, class, phone, field, difference: :func:`app.models.colouring.point_colors`), with the
selected frame or state marked in every view. The field is the state's
:attr:`~app.models.state.AppState.color_field` (chosen by the colour box, or by the Compare
panel), its levels those the field filter shows, at most :data:`MAX_MULTIPLES`. All views share
one camera with the manifold view (the window links them: :mod:`app.views.camera_link`), so
turning one turns all; selection and horizon are the state's, so they are linked by design.
The views are drawn only while the dock shows them.
"""
from __future__ import annotations

import numpy as np
from PySide6 import QtCore, QtWidgets

from app import scene
from app.models.colour_maps import RESERVED_COLOURS
from app.views._common import RenderScheduler, close_plotter, connect_all, disconnect_all, elided_label, make_plotter

__all__ = ["SmallMultiples", "MAX_MULTIPLES", "MAX_POINTS", "GRID", "NO_FIELD"]

#: what the dock says while no field is chosen
NO_FIELD = ("No field chosen. Colour › Field … (or the Compare panel) chooses a per-utterance field, "
            "such as speaker or condition: one view per level then appears here, all turned by one camera.")

#: views at most (a field with more levels shows its first ones; filter it to choose)
MAX_MULTIPLES = 6
#: the renderer grid the views are laid out on
GRID = (2, 3)
#: frames drawn per view at most (evenly taken when a level has more)
MAX_POINTS = 20000
#: what changes the views' colours (as the manifold view recolours)
_RECOLOUR = {"color_mode", "hemisphere", "horizon_ms", "phone_filter", "visible_phones", "field_filter",
             "color_field", "comparison", "palette", "utterance"}


def layout_viewports(n: int) -> list[tuple]:
    """The viewport (x0, y0, x1, y1) of each of ``n`` views: one row up to three, else two rows of three."""
    rows = 1 if n <= GRID[1] else GRID[0]
    cols = n if rows == 1 else GRID[1]
    out = []
    for k in range(n):
        r, c = divmod(k, cols)
        out.append((c / cols, 1.0 - (r + 1) / rows, (c + 1) / cols, 1.0 - r / rows))
    return out


class SmallMultiples(QtWidgets.QWidget):
    """One view per level of a field (module docstring), bound to an :class:`app.models.state.AppState`.

    Attributes
    ----------
    field : str or None
    levels : list of str
        The levels shown, one view each.
    frames : list of ndarray
        The frames each view draws.
    """

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.state = state
        self.field, self.levels, self.frames, self.views = None, [], [], []
        self._stale = True
        self.plotter = make_plotter(self, shape=GRID)
        self.renderer = RenderScheduler(self.plotter)
        self.caption = elided_label("")
        # no field chosen: this says how to choose one, in place of an empty (black) 3-D view
        self.placeholder = QtWidgets.QLabel(NO_FIELD)
        self.placeholder.setWordWrap(True)
        self.placeholder.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.placeholder.setStyleSheet("color: #555")
        lay = QtWidgets.QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.setSpacing(1)
        lay.addWidget(self.plotter.interactor, 1)
        lay.addWidget(self.placeholder, 1)
        lay.addWidget(self.caption)
        self._show_placeholder(True)
        self._connections = [(state.events.changed, self._on_changed)]
        connect_all(self._connections)

    # ------------------------------------------------------------------ linking
    def link_camera(self, camera) -> None:
        """Show every view through ``camera`` (the manifold view's: turning one turns all)."""
        self._camera = camera
        for ren in self.plotter.renderers:
            ren.SetActiveCamera(camera)

    # ------------------------------------------------------------------ what is shown
    def wanted(self) -> tuple:
        """``(field, levels)`` the views should show now."""
        from app.models.field_colouring import field_levels, utterance_field_values

        s = self.state
        name = s.color_field
        if s.manifold is None or name is None or name not in utterance_field_values(s):
            return None, []
        levels = field_levels(s, name)
        shown = s.field_levels_shown(name)
        if shown:
            levels = [lv for lv in levels if lv in shown]
        return name, levels[:MAX_MULTIPLES]

    def _on_changed(self, names) -> None:
        if not self.isVisible():
            self._stale = True
            return
        if names & {"manifold", "color_field", "field_filter", "palette"} or self._stale:
            self.refresh()
            return
        if names & _RECOLOUR or ("state" in names and self.state.color_mode == "distance"):
            self._recolour()
        if names & {"frame", "state"}:
            self._mark_selection()
        if names & (_RECOLOUR | {"frame", "state"}):
            self.renderer.request()

    def showEvent(self, event):
        super().showEvent(event)
        if self._stale:
            self.refresh()

    def refresh(self) -> None:
        """Rebuild the views for the field and levels wanted now."""
        self._stale = False
        p = self.plotter
        for ren in p.renderers:
            ren.RemoveAllViewProps()
        self.views = []
        self.field, self.levels = self.wanted()
        s = self.state
        self.frames = []
        if self.field is not None:
            from app.models.comparison import level_frames
            from app.models.field_colouring import utterance_field_values

            values = utterance_field_values(s)[self.field]
            uidx = s.manifold.corpus_.utterance_index
            for lv in self.levels:
                f = level_frames(values, uidx, lv)
                if len(f) > MAX_POINTS:
                    f = f[np.linspace(0, len(f) - 1, MAX_POINTS).astype(np.int64)]
                self.frames.append(f)
        ports = layout_viewports(len(self.levels))
        L = scene.scene_scale(s.cloud.bounds) if s.manifold is not None else 1.0
        for k, ren in enumerate(p.renderers):
            if k >= len(self.levels):
                ren.SetViewport(0.0, 0.0, 0.0, 0.0)
                ren.SetDraw(False)
                continue
            ren.SetDraw(True)
            ren.SetViewport(*ports[k])
            p.subplot(*divmod(k, GRID[1]))
            f = self.frames[k]
            Y = np.asarray(s.manifold.Fy_[f])[:, :3] if len(f) else np.zeros((1, 3))
            small = len(Y) <= 10000
            pts = scene.add_manifold_points(p, Y, point_size=4.0 if small else 3.0, spheres=small,
                                            name=f"level_points_{k}")
            marker = scene.add_marker(p, None, 0.025 * L, color=RESERVED_COLOURS["selected"], name=f"level_mark_{k}")
            rgb = s.palette.colour(f"field:{self.field}", self.levels[k]) if s.palette is not None else (0, 0, 0)
            n_utt = len(np.unique(s.manifold.corpus_.utterance_index[f])) if len(f) else 0
            p.add_text(f"{self.levels[k]} ({n_utt} utt.)", position="upper_left", font_size=9, color=rgb,
                       name=f"level_title_{k}")
            self.views.append({"points": pts, "marker": marker})
        if getattr(self, "_camera", None) is not None:
            self.link_camera(self._camera)
        self._show_placeholder(self.field is None)
        if self.field is not None:
            more = len(self.wanted()[1]) < len(self._all_levels())
            self.caption.setText(f"{self.field}: {', '.join(self.levels)}" + (
                f" (the first {MAX_MULTIPLES}; Filter chooses)" if more else "")
                + " · colours as the manifold view's; one camera")
        self._recolour()
        self._mark_selection()
        self.renderer.request()

    def _show_placeholder(self, on: bool) -> None:
        self.plotter.interactor.setVisible(not on)
        self.caption.setVisible(not on)
        self.placeholder.setVisible(on)

    def _all_levels(self) -> list:
        from app.models.field_colouring import field_levels

        shown = self.state.field_levels_shown(self.field)
        levels = field_levels(self.state, self.field)
        return [lv for lv in levels if not shown or lv in shown]

    def _recolour(self) -> None:
        from app.models.colouring import point_colors

        if not self.views:
            return
        s = self.state
        c = point_colors(s.color_mode, s.manifold, s)
        group = s.cloud.group_of
        for view, f in zip(self.views, self.frames):
            if len(f):
                view["points"].set_colors(c.rgb[group[f]])

    def _mark_selection(self) -> None:
        s = self.state
        where = None
        if s.frame is not None:
            where = np.asarray(s.manifold.Fy_[s.frame])[:3]
        elif s.state is not None:
            where = s.manifold.states_.centroids_[s.state, :3]
        for view in self.views:
            if where is None:
                view["marker"].set_visible(False)
            else:
                view["marker"].move(where)

    def close_view(self) -> None:
        disconnect_all(self._connections)
        self.renderer.stop()
        close_plotter(self.plotter)
