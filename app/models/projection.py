"""World -> screen (numpy only): a view's camera matrix, projected points, hover look-up, standard views.

The hover readout and the vector export both need where each point lands on the
screen; the VTK side is one function (:func:`view_transform`), the rest is numpy.
"""
from __future__ import annotations

import numpy as np

__all__ = ["view_transform", "project", "nearest_on_screen", "standard_camera", "STANDARD_VIEWS"]

STANDARD_VIEWS = ("side", "top", "default")


def view_transform(plotter, renderer=None) -> tuple[np.ndarray, tuple[int, int]]:
    """The active camera's world -> normalised device matrix and the renderer's size in pixels.

    Returns
    -------
    M : ndarray of shape (4, 4)
        ``M @ [x, y, z, 1]`` gives clip coordinates; divide by w for [-1, 1]^3.
    size : (width, height) in pixels of the renderer's viewport
    """
    ren = plotter.renderer if renderer is None else renderer
    w, h = (int(v) for v in ren.GetSize())
    cam = ren.GetActiveCamera()
    vtk_m = cam.GetCompositeProjectionTransformMatrix(w / max(h, 1), -1.0, 1.0)
    M = np.array([[vtk_m.GetElement(r, c) for c in range(4)] for r in range(4)], dtype=np.float64)
    return M, (w, h)


def project(Y, M, size) -> tuple[np.ndarray, np.ndarray]:
    """Display positions (pixels, origin bottom left) and depths of world points.

    Parameters
    ----------
    Y : ndarray of shape (N, >=3)
    M : ndarray of shape (4, 4) from :func:`view_transform`
    size : (width, height)

    Returns
    -------
    xy : ndarray of shape (N, 2) float64
    depth : ndarray of shape (N,) float64
        Normalised device depth in [-1, 1] for points inside the view volume; larger = farther.
    """
    Y = np.asarray(Y, dtype=np.float64)
    if Y.ndim != 2 or Y.shape[1] < 3:
        raise ValueError(f"points must have shape (N, 3), got {Y.shape}")
    P = Y[:, :3] @ M[:3, :3].T + M[:3, 3]
    w = Y[:, :3] @ M[3, :3] + M[3, 3]
    w = np.where(np.abs(w) < 1e-300, 1e-300, w)
    ndc = P / w[:, None]
    W, H = size
    xy = np.column_stack([(ndc[:, 0] + 1) * 0.5 * W, (ndc[:, 1] + 1) * 0.5 * H])
    return xy, ndc[:, 2]


def nearest_on_screen(xy, depth, mouse, radius: float = 6.0):
    """The point under the mouse: within ``radius`` pixels, the one nearest the camera.

    Parameters
    ----------
    xy : ndarray of shape (N, 2), depth : ndarray of shape (N,)
        From :func:`project`.
    mouse : (x, y) display position (pixels, origin bottom left)
    radius : float, default=6

    Returns
    -------
    int or None
        Index of the point, None when no point is that close (or every close one is
        behind the camera / outside the depth range).
    """
    xy = np.asarray(xy, dtype=np.float64)
    depth = np.asarray(depth, dtype=np.float64)
    mx, my = (float(v) for v in mouse)
    d2 = (xy[:, 0] - mx) ** 2 + (xy[:, 1] - my) ** 2
    near = np.flatnonzero((d2 <= float(radius) ** 2) & (np.abs(depth) <= 1.0))
    if near.size == 0:
        return None
    return int(near[np.argmin(depth[near])])


def standard_camera(name: str, Y, plane_point, S, V) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Camera (position, focal point, view up) of a standard view of the manifold.

    * ``"side"``: the S–V plane face on, V (opening) up: the zero-velocity plane is seen
      edge on, the opening half above it and the closing half below;
    * ``"top"``: looking down V onto the zero-velocity plane, S to the right;
    * ``"default"``: the side view raised 25° and turned 30° about V, so the plane is seen
      slightly from above and both halves stay apart.

    The camera looks at the cloud's centre from 2.5 times its largest extent.
    """
    if name not in STANDARD_VIEWS:
        raise ValueError(f"view must be one of {STANDARD_VIEWS}, got {name!r}")
    Y = np.asarray(Y, dtype=np.float64)[:, :3]
    S = np.asarray(S, dtype=np.float64)
    V = np.asarray(V, dtype=np.float64)
    V = V / np.linalg.norm(V)
    S = S - (S @ V) * V  # orthogonal to V
    S = S / np.linalg.norm(S)
    W = np.cross(S, V)  # towards the viewer of the side view (S right, V up)
    centre = 0.5 * (Y.min(0) + Y.max(0))
    dist = 2.5 * float(max(np.ptp(Y, axis=0).max(), 1e-9))
    if name == "side":
        d, up = W, V
    elif name == "top":
        d, up = V, np.cross(V, S)
    else:
        el, az = np.radians(25.0), np.radians(30.0)
        d = np.cos(el) * (np.cos(az) * W + np.sin(az) * S) + np.sin(el) * V
        up = V - (V @ d) * d
        up /= np.linalg.norm(up)
    return centre + dist * d, centre, up
