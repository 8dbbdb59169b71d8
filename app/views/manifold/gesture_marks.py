"""The manifold view's marks of the gestural landmarks: where each landmark of the current utterance's gestures
lies on the manifold (a mixin of the view).

The landmarks are the state's :attr:`app.models.state.AppState.gestures` (as edited in the
editor's gesture tier), those of the current utterance; each is an octahedron
(:func:`app.scene.marks.add_landmark_marks`) at its frame in Y1-3, in the landmark's palette
colour, drawn over the cloud, and named in the glyph legend.
"""
from __future__ import annotations

import numpy as np

from app import scene
from app.models.signals import landmark_colour
from app.scene.marks import add_landmark_marks
from engine.recordings.signals.gestures import LANDMARKS

__all__ = ["GestureMarks"]


class GestureMarks:
    """Landmark marks of :class:`app.views.manifold_view.ManifoldView`."""

    #: a mark's radius, as a share of the cloud's extent
    MARK_SIZE = 0.012

    def _add_gesture_marks(self, L: float) -> None:
        self.handles["landmarks"] = add_landmark_marks(self.plotter, size=self.MARK_SIZE * L)
        scene.move_to_overlay(self.plotter, self.handles["landmarks"])
        self._landmarks_shown = ()

    def _on_gesture_marks(self, render=True) -> None:
        h = self.handles.get("landmarks")
        if h is None:
            return
        s = self.state
        gs, uid = s.gestures, s.utterance
        shown = ()
        if gs is None or uid is None or uid not in gs.utterance_ids:
            h.update(None, None)
        else:
            f = gs.frames(s.manifold.corpus_.bounds)[gs.of_utterance(uid)]
            cols = np.broadcast_to(np.arange(len(LANDMARKS)), f.shape)
            keep = f >= 0
            colours = np.asarray([landmark_colour(s.palette, n) for n in LANDMARKS], np.float32)
            h.update(np.asarray(s.manifold.Fy_[f[keep]])[:, :3], colours[cols[keep]])
            shown = tuple(LANDMARKS[j] for j in sorted(set(cols[keep].tolist())))
        if shown != self._landmarks_shown:
            self._landmarks_shown = shown
            self._update_legends()
        if render:
            self.renderer.request()

    def landmark_rows(self) -> list:
        """``(code, rgb)`` of the landmarks marked now, in gesture order (the glyph legend's rows)."""
        return [(n, landmark_colour(self.state.palette, n)) for n in getattr(self, "_landmarks_shown", ())]
