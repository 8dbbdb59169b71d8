"""Click picking on one actor: a click (press and release without dragging) picks a point.

pyvista's own left-click picking fires on every button press, so rotating the view
would select points. :class:`ClickPicker` watches press and release, picks only
when the mouse did not move, restricts the picker to one actor and reports the
picked point id, its position and whether Shift was held.

A click also keeps the camera style from rendering on button release (it renders
whenever an interaction ends, though a click moved nothing): the selection the
click makes asks for the one render it needs, so a click costs one frame, not two.
"""
from __future__ import annotations

import numpy as np

__all__ = ["ClickPicker", "enable_click_picking", "pick_display_point"]


def pick_display_point(plotter, xyz) -> tuple[float, float]:
    """Display (pixel) coordinates of world point ``xyz`` in ``plotter``'s renderer."""
    ren = plotter.renderer
    x, y, z = (float(v) for v in np.asarray(xyz, dtype=np.float64).reshape(3))
    ren.SetWorldPoint(x, y, z, 1.0)
    ren.WorldToDisplay()
    dx, dy, _ = ren.GetDisplayPoint()
    return float(dx), float(dy)


class ClickPicker:
    """Pick points of ``actor`` on click; calls ``callback(point_id, xyz, shift)``.

    Parameters
    ----------
    plotter : pyvista plotter (observers are added only when it has an interactor)
    actor : the actor whose points are pickable
    callback : callable(int, ndarray (3,) or None, bool)
    tolerance : float, default=0.01
        Pick tolerance as a fraction of the window diagonal.
    max_move : int, default=4
        Pixels the mouse may move between press and release for a click.
    locate : callable((x, y)) -> int or None, optional
        Finds what a click at a display position picks (e.g.
        :meth:`app.models.picking.CloudLocator.locate`, which searches frames the view does not
        draw); the callback then gets its result and ``xyz=None``. Default: VTK's point
        picker on ``actor``.
    """

    def __init__(self, plotter, actor, callback, *, tolerance: float = 0.01, max_move: int = 4, locate=None):
        from vtkmodules.vtkRenderingCore import vtkPointPicker

        self.plotter = plotter
        self.callback = callback
        self.locate = locate
        self.max_move = int(max_move)
        self.picker = vtkPointPicker()
        self.picker.SetTolerance(float(tolerance))
        self.picker.PickFromListOn()
        self.picker.AddPickList(actor)
        self._press = None
        self._observers = []
        self._style_observers = []
        self._muted = False
        iren = getattr(plotter, "iren", None)
        if iren is not None and getattr(iren, "interactor", None) is not None:
            self._observers = [iren.add_observer("LeftButtonPressEvent", self._on_press),
                               iren.add_observer("LeftButtonReleaseEvent", self._on_release)]
            style = iren.interactor.GetInteractorStyle()
            # Only a style that already hands its release events to observers (pyvista's capture
            # styles) may get more: on a plain VTK style, any observer replaces OnLeftButtonUp.
            if style is not None and style.HasObserver("LeftButtonReleaseEvent"):
                self._style = style
                self._style_observers = [style.AddObserver("LeftButtonReleaseEvent", self._mute, 10.0),
                                         style.AddObserver("LeftButtonReleaseEvent", self._unmute, -10.0)]

    def _interactor(self):
        return self.plotter.iren.interactor  # the vtkRenderWindowInteractor (observers get the style)

    def _on_press(self, _obj, _event):
        self._press = tuple(self._interactor().GetEventPosition())

    def _is_click(self) -> bool:
        if self._press is None:
            return False
        pos = tuple(self._interactor().GetEventPosition())
        return max(abs(pos[0] - self._press[0]), abs(pos[1] - self._press[1])) <= self.max_move

    def _mute(self, _obj, _event):
        """Before the style ends its interaction: no render for a click."""
        if self._is_click():
            self._interactor().EnableRenderOff()
            self._muted = True

    def _unmute(self, _obj, _event):
        if self._muted:
            self._muted = False
            self._interactor().EnableRenderOn()

    def _on_release(self, _obj, _event):
        iren = self._interactor()
        pos = tuple(iren.GetEventPosition())
        press, self._press = self._press, None
        if press is None or max(abs(pos[0] - press[0]), abs(pos[1] - press[1])) > self.max_move:
            return
        self.pick(pos[0], pos[1], shift=bool(iren.GetShiftKey()))

    def pick(self, x: float, y: float, *, shift: bool = False):
        """Pick at display position (x, y); returns the point id or None if nothing is there."""
        if self.locate is not None:
            pid = self.locate((float(x), float(y)))
            if pid is not None:
                self.callback(int(pid), None, bool(shift))
            return pid
        self.picker.Pick(float(x), float(y), 0.0, self.plotter.renderer)
        pid = int(self.picker.GetPointId())
        if pid < 0:
            return None
        self.callback(pid, np.array(self.picker.GetPickPosition()), bool(shift))
        return pid

    def remove(self) -> None:
        iren = getattr(self.plotter, "iren", None)
        if iren is not None:
            for obs in self._observers:
                iren.remove_observer(obs)
        for obs in self._style_observers:
            self._style.RemoveObserver(obs)
        self._observers, self._style_observers = [], []


def enable_click_picking(plotter, actor, callback, **kw) -> ClickPicker:
    """Make clicks on ``actor`` call ``callback(point_id, xyz, shift)``; see :class:`ClickPicker`."""
    return ClickPicker(plotter, actor, callback, **kw)
