"""The manifold view's camera: the standard views and "frame the selection".

A part of :class:`app.views.manifold_view.ManifoldView` (a mixin). A standard view ("side", the
S–V plane face on; "top", down V; "default") frames the whole cloud with its labels; framing
the selection (View › Frame selection, F) keeps the direction of view and brings the chosen
clusters and the selection (:func:`app.models.framing.selection_bounds`) to fill the view.
"""
from __future__ import annotations

import numpy as np

from app import scene
from app.models.framing import selection_bounds
from app.scene.projection import project, standard_camera, view_transform

__all__ = ["ManifoldCamera"]


class ManifoldCamera:
    """The camera of :class:`app.views.manifold_view.ManifoldView`."""

    def standard_view(self, name: str, render: bool = True) -> None:
        """Put the camera in a standard view: "side" (S–V plane), "top" (down V) or "default"."""
        m = self.state.manifold
        if m is None or "points" not in self.handles:
            return
        t = m.tangent_
        # the cloud's bounds stand for every frame (the camera only reads their extent)
        pos, focal, up = standard_camera(name, self.state.cloud.bounds, t.plane_point_, t.S_, t.plane_normal_)
        cam = self.plotter.renderer.GetActiveCamera()
        cam.SetPosition(*pos)
        cam.SetFocalPoint(*focal)
        cam.SetViewUp(*up)
        ren = self.plotter.renderer
        lo, hi = np.reshape(self.handles["points"].mesh.bounds, (3, 2)).T
        tips = self._label_tips()
        if tips is not None:  # the S, V and Y labels stand beyond the cloud: frame them too
            lo, hi = np.minimum(lo, tips.min(axis=0)), np.maximum(hi, tips.max(axis=0))
        ren.ResetCamera(*np.column_stack([lo, hi]).ravel())  # fit the cloud and the labels, same direction
        if tips is not None:  # and keep the labels' text inside the view, not cut at its edge
            for _ in range(2):
                M, size = view_transform(self.plotter)
                xy = project(tips, M, size)[0]
                pads = self._label_pads()
                z = min(scene.label_zoom(xy[k:k + 1], size, pad=pads[k]) for k in range(len(xy)))
                if z >= 0.999:
                    break
                cam.Zoom(z)
        ren.ResetCameraClippingRange()
        if render:
            self.renderer.request()

    def _label_pads(self) -> list:
        """For each label tip, how far (pixels) its text reaches from it: half the text's width and a margin."""
        from app.scene.axes import AXIS_LABEL_PX
        from app.scene.manifold import AXES_LABEL_PX

        pads = []
        for key in ("axes", "yaxes"):
            h = self.handles.get(key)
            if isinstance(h, dict) and "tips" in h:
                if key == "yaxes":
                    pads += [0.3 * AXIS_LABEL_PX * len(t) + AXIS_LABEL_PX for t in h["names"]]
                else:
                    pads += [1.5 * AXES_LABEL_PX] * len(h["tips"])
        return pads

    def _label_tips(self):
        """Where the S, V and Y labels stand (n, 3), or None."""
        tips = [h["tips"] for key in ("axes", "yaxes") if isinstance(h := self.handles.get(key), dict) and "tips" in h]
        return np.vstack(tips) if tips else None

    def frame_selection(self, render: bool = True) -> bool:
        """Bring the chosen clusters and the selection into view, keeping the direction of view.

        With nothing chosen the whole cloud is framed (the default view's framing from the
        current direction). Returns whether there was something chosen to frame.
        """
        if self.state.manifold is None or "points" not in self.handles:
            return False
        box = selection_bounds(self.state)
        chosen = box is not None
        if box is None:
            lo, hi = np.reshape(self.handles["points"].mesh.bounds, (3, 2)).T
        else:
            lo, hi = box
        ren = self.plotter.renderer
        ren.ResetCamera(*np.column_stack([lo, hi]).ravel())
        ren.ResetCameraClippingRange()
        if render:
            self.renderer.request()
        return chosen
