"""Marks at chosen frames of the manifold, each in its own colour: the gestural landmarks of an utterance.

:func:`add_landmark_marks` draws one small octahedron per mark (a form neither the cloud's dots
nor the selection's sphere has), coloured per mark; :meth:`MarksHandle.update` replaces them in
place (the same actor), or hides them. Takes any pyvista plotter.
"""
from __future__ import annotations

import numpy as np
import pyvista as pv

from app.scene.handles import Handle
from app.scene.manifold import to_rgb8

__all__ = ["MarksHandle", "add_landmark_marks"]


class MarksHandle(Handle):
    """Octahedra at points, one colour each; :meth:`update` changes them in place.

    ``points`` (n, 3) and ``rgb`` (n, 3) uint8 hold what is drawn (for tests and tools).
    """

    points = np.zeros((0, 3))
    rgb = np.zeros((0, 3), np.uint8)

    def __init__(self, plotter, mesh, actor, size):
        super().__init__(plotter, mesh, actor)
        self.size = float(size)

    def update(self, Y, rgb) -> None:
        """Draw marks at ``Y`` (n, >=3) in colours ``rgb`` (n, 3); none (or n = 0) hides them."""
        if Y is None or len(Y) == 0:
            self.points, self.rgb = np.zeros((0, 3)), np.zeros((0, 3), np.uint8)
            self.set_visible(False)
            return
        Y = np.asarray(Y, np.float64)[:, :3]
        rgb8 = to_rgb8(rgb)
        if rgb8.shape != (len(Y), 3):
            raise ValueError(f"colours must have shape ({len(Y)}, 3), got {rgb8.shape}")
        self.points, self.rgb = Y, rgb8
        src = pv.PolyData(Y.astype(np.float32))
        src.point_data["rgb"] = rgb8
        glyphs = src.glyph(geom=_octahedron(self.size), scale=False, orient=False)
        self.replace_geometry(glyphs)
        self.set_visible(True)


def _octahedron(size: float):
    return pv.PlatonicSolid("octahedron", radius=float(size))


def add_landmark_marks(plotter, *, size: float = 1.0, name: str = "landmark_marks") -> MarksHandle:
    """An empty, hidden set of marks (octahedra of radius ``size``); fill it with :meth:`MarksHandle.update`."""
    src = pv.PolyData(np.zeros((1, 3), np.float32))
    src.point_data["rgb"] = np.zeros((1, 3), np.uint8)
    mesh = src.glyph(geom=_octahedron(size), scale=False, orient=False)
    actor = plotter.add_mesh(mesh, scalars="rgb", rgb=True, name=name, pickable=False, show_scalar_bar=False,
                             reset_camera=False, render=False)
    h = MarksHandle(plotter, mesh, actor, size)
    h.set_visible(False)
    return h
