"""One camera shown in several 3-D views: when it moves, every view showing it renders once.

The manifold view and the small multiples share one ``vtkCamera`` (the window links them,
:meth:`app.views.small_multiples.SmallMultiples.link_camera`). Whichever view the user turns,
the camera changes; :class:`CameraLink` observes it and asks each linked view's
:class:`app.views._common.RenderScheduler` for a render, only when its pose (position, focal
point, view up, view angle or parallel scale) changed: a render itself touches the camera's
clipping range, which must not ask for another render.
"""
from __future__ import annotations

__all__ = ["CameraLink", "camera_pose"]


def camera_pose(camera) -> tuple:
    """What a camera shows, rounded to 1e-9 (its clipping range left out)."""
    vals = (*camera.GetPosition(), *camera.GetFocalPoint(), *camera.GetViewUp(), camera.GetViewAngle(),
            camera.GetParallelScale(), float(camera.GetParallelProjection()))
    return tuple(round(float(v), 9) for v in vals)


class CameraLink:
    """Render every linked view when ``camera``'s pose changes (but the one being turned, which renders itself).

    Parameters
    ----------
    camera : vtkCamera
    plotters : sequence of (plotter, RenderScheduler)
        The views showing ``camera``; a plotter's interactor tells which one the user is turning.
    """

    def __init__(self, camera, plotters):
        self.camera = camera
        self.views = list(plotters)
        self.n_moves = 0
        self.active = None  # the scheduler of the view being turned (it renders itself)
        self._pose = camera_pose(camera)
        self._tags = [(camera, camera.AddObserver("ModifiedEvent", self._on_modified))]
        for plotter, sched in self.views:
            iren = getattr(getattr(plotter, "iren", None), "interactor", None)
            if iren is not None:
                for button in ("Left", "Middle", "Right"):  # a view turned with a button held renders itself
                    for ev, who in ((f"{button}ButtonPressEvent", sched), (f"{button}ButtonReleaseEvent", None)):
                        self._tags.append((iren, iren.AddObserver(ev, lambda _o, _e, w=who: self._turning(w))))

    def _turning(self, scheduler) -> None:
        self.active = scheduler

    def _on_modified(self, _obj, _event) -> None:
        pose = camera_pose(self.camera)
        if pose == self._pose:
            return
        self._pose = pose
        self.n_moves += 1
        for _plotter, sched in self.views:
            if sched is not self.active:
                sched.request()

    def remove(self) -> None:
        for obj, tag in self._tags:
            obj.RemoveObserver(tag)
        self._tags = []
