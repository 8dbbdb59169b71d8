"""From a click in a 3-D view to a frame index: pure functions, then the state.

The manifold view's VTK callback hands the click's display position to
:meth:`CloudLocator.locate`, which finds the frame under the cursor among *all*
frames, also those a level-of-detail cloud does not draw (:mod:`app.models.lod`), by
:func:`frame_under_cursor`; :func:`handle_pick` puts it in the state
(:meth:`app.models.state.AppState.select_frame`). Each layer is tested on its own.
:func:`pick_to_frame` and :class:`PointLocator` map a picked position in the view's
coordinates to the nearest frame.
"""
from __future__ import annotations

import numpy as np

__all__ = ["pick_to_frame", "PointLocator", "frame_under_cursor", "CloudLocator", "handle_pick", "hover_text"]


def pick_to_frame(picked, Fy3) -> int:
    """The frame whose F^y point is nearest to the picked point.

    Parameters
    ----------
    picked : sequence of 3 floats, or int
        The picked position in the view's coordinates, or a point id of the
        manifold's point cloud (returned as is after a range check).
    Fy3 : ndarray of shape (N, 3)
        The drawn points (the first three dims of F^y).

    Returns
    -------
    int
    """
    Fy3 = np.asarray(Fy3)
    if Fy3.ndim != 2 or Fy3.shape[1] != 3 or Fy3.shape[0] == 0:
        raise ValueError(f"Fy3 must have shape (N, 3) with N > 0, got {Fy3.shape}")
    if isinstance(picked, (int, np.integer)) and not isinstance(picked, (bool, np.bool_)):
        i = int(picked)
        if not 0 <= i < Fy3.shape[0]:
            raise IndexError(f"picked point id {i} out of range 0..{Fy3.shape[0] - 1}")
        return i
    p = np.asarray(picked, dtype=np.float64).reshape(-1)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"picked point must be 3 finite coordinates or a point id, got {picked!r}")
    d = ((Fy3.astype(np.float64) - p) ** 2).sum(axis=1)
    return int(np.argmin(d))


class PointLocator:
    """Nearest-frame look-up with a KD-tree built once (for large manifolds)."""

    def __init__(self, Fy3):
        from scipy.spatial import cKDTree

        self.Fy3 = np.asarray(Fy3, dtype=np.float64)
        if self.Fy3.ndim != 2 or self.Fy3.shape[1] != 3 or self.Fy3.shape[0] == 0:
            raise ValueError(f"Fy3 must have shape (N, 3) with N > 0, got {self.Fy3.shape}")
        self._tree = cKDTree(self.Fy3)

    def __call__(self, picked) -> int:
        if isinstance(picked, (int, np.integer)) and not isinstance(picked, (bool, np.bool_)):
            return pick_to_frame(picked, self.Fy3)
        p = np.asarray(picked, dtype=np.float64).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"picked point must be 3 finite coordinates or a point id, got {picked!r}")
        return int(self._tree.query(p)[1])


def frame_under_cursor(xy, depth, mouse, *, dot_radius: float, radius: float):
    """Which of the projected frames a click at ``mouse`` selects (pure; indices into ``xy``).

    What the user sees under the cursor: of the frames whose dot covers it (its centre
    within ``dot_radius`` pixels), the one nearest the camera (it is drawn over the
    others); when no dot covers the cursor, the frame whose centre is nearest to it
    within ``radius`` pixels (the nearer to the camera on a tie); None when there is none.

    Parameters
    ----------
    xy : ndarray of shape (n, 2)
        Display positions (pixels, origin bottom left), from
        :func:`app.models.projection.project`.
    depth : ndarray of shape (n,)
        Normalised device depths (larger = farther; outside [-1, 1]: not in view).
    mouse : (x, y)
    dot_radius, radius : float
        Half the drawn point size, and the pick tolerance (pixels).

    Returns
    -------
    int or None
    """
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    depth = np.asarray(depth, dtype=np.float64).reshape(-1)
    mx, my = (float(v) for v in mouse)
    d2 = (xy[:, 0] - mx) ** 2 + (xy[:, 1] - my) ** 2
    seen = np.abs(depth) <= 1.0
    cover = np.flatnonzero(seen & (d2 <= float(dot_radius) ** 2))
    if cover.size:
        return int(cover[np.lexsort((d2[cover], depth[cover]))[0]])
    near = np.flatnonzero(seen & (d2 <= float(radius) ** 2))
    if near.size == 0:
        return None
    return int(near[np.lexsort((depth[near], d2[near]))[0]])


class CloudLocator:
    """The frame under the cursor in a view of a (level-of-detail) cloud, searched among all frames.

    A drawn point stands for its group's frames (:class:`app.models.lod.CloudDetail`), each within
    the group's ``radius`` of it in Y1-3. For a click, the groups whose frames could lie
    within the pick tolerance on screen (their drawn point within the tolerance plus the
    projected radius, a bound that holds for any perspective) are found among the
    drawn points (projected once per camera), their frames projected, and
    :func:`frame_under_cursor` chooses. The result is the frame :func:`frame_under_cursor`
    would choose among every frame of the corpus.

    Parameters
    ----------
    Fy : ndarray of shape (N, >=3)
        The frames in F^y (only Y1-3 are read, and only for the candidates).
    cloud : app.models.lod.CloudDetail
    dot_radius : float, default=1.75
        Half the drawn point size in pixels.
    radius : float, default=6.0
        Pick tolerance in pixels.
    """

    def __init__(self, Fy, cloud, *, dot_radius: float = 1.75, radius: float = 6.0):
        self.Fy, self.cloud = Fy, cloud
        self.dot_radius, self.radius = float(dot_radius), float(radius)
        self.points = np.asarray(Fy[cloud.frames, :3], dtype=np.float64)  # the drawn points
        self._key = None
        self.n_candidates = 0  # frames projected for the last query (for benchmarks)

    def _project_points(self, M, size):
        from app.models.projection import project

        key = (np.asarray(M).tobytes(), tuple(size))
        if self._key != key:
            xy, _depth = project(self.points, M, size)
            reach = np.zeros(len(xy))
            rad = self.cloud.radius
            some = np.flatnonzero(rad > 0)
            if some.size:
                reach[some] = _screen_reach(self.points[some], rad[some], M, size)
            self._key, self._xy, self._reach = key, xy, reach
        return self._xy, self._reach

    def candidates(self, mouse, M, size, *, radius: float | None = None) -> np.ndarray:
        """Frames that could lie within the pick tolerance (``radius`` pixels) of ``mouse`` on screen (sorted)."""
        radius = self.radius if radius is None else float(radius)
        xy, reach = self._project_points(M, size)
        mx, my = (float(v) for v in mouse)
        d = np.hypot(xy[:, 0] - mx, xy[:, 1] - my)
        groups = np.flatnonzero(~(d > max(radius, self.dot_radius) + reach))  # NaN positions stay in
        return np.sort(self.cloud.members(groups))

    def locate(self, mouse, M, size, *, radius: float | None = None):
        """The frame a click at display position ``mouse`` selects, or None (see :func:`frame_under_cursor`);
        ``radius`` overrides the pick tolerance."""
        from app.models.projection import project

        radius = self.radius if radius is None else float(radius)
        frames = self.candidates(mouse, M, size, radius=radius)
        self.n_candidates = int(frames.size)
        if frames.size == 0:
            return None
        xy, depth = project(np.asarray(self.Fy[frames, :3], dtype=np.float64), M, size)
        i = frame_under_cursor(xy, depth, mouse, dot_radius=self.dot_radius, radius=radius)
        return None if i is None else int(frames[i])


def _screen_reach(centres, rad, M, size) -> np.ndarray:
    """Pixels that a point within ``rad`` of each centre can lie from the centre's projection (an upper
    bound; inf where the sphere reaches the camera's plane, -inf where it lies wholly behind the camera:
    nothing of it is in view)."""
    M = np.asarray(M, dtype=np.float64)
    W, H = size
    w = centres @ M[3, :3] + M[3, 3]
    ndc = (centres @ M[:2, :3].T + M[:2, 3]) / np.where(w == 0, 1e-300, w)[:, None]
    m = np.linalg.norm(M[3, :3])
    # x_ndc(c + d) - x_ndc(c) = (a.d - x_ndc m.d) / (w + m.d) for a row a of M:
    # bounded by (|a| + |x_ndc||m|) r / (w - |m| r)
    ax, ay = np.linalg.norm(M[0, :3]), np.linalg.norm(M[1, :3])
    margin = w - m * rad
    px = np.hypot(0.5 * W * (ax + np.abs(ndc[:, 0]) * m), 0.5 * H * (ay + np.abs(ndc[:, 1]) * m)) * rad
    reach = np.where(margin > 0, px / np.where(margin > 0, margin, 1.0), np.inf)
    return np.where(w + m * rad <= 0, -np.inf, reach)


def handle_pick(state, picked, locator=None, *, as_target: bool | None = None) -> int:
    """Select the frame ``picked`` (through ``locator`` when given: the nearest to a position) in
    ``state``; returns the frame index.

    ``as_target`` True makes its state the path target (a shift-click or the path
    toggle); None lets :attr:`AppState.path_mode` decide.
    """
    i = int(picked) if locator is None else locator(picked)
    state.select_frame(i, as_target=as_target)
    return i


def hover_text(manifold, phones, i) -> str:
    """The readout of frame ``i`` under the pointer: frame, utterance, time, phone, state, tangent class.

    ``phones``: every frame's phone label, or an :class:`app.models.state.AppState` (its
    :meth:`~app.models.state.AppState.phone_of` and :meth:`~app.models.state.AppState.utterance_of`, no
    per-frame arrays are built).
    """
    from app.models.colouring import CLASS_LABELS

    c = manifold.corpus_
    if hasattr(phones, "phone_of"):
        u, ph = phones.utterance_of(i), phones.phone_of(i)
    else:
        u, ph = c.utterances[int(np.searchsorted(c.bounds[:, 0], i, side="right")) - 1], phones[i]
    cls = int(manifold.tangent_.classes_[i])
    return (f"frame {i} ({u.id}, t={(i - u.start) / c.rate:.3f} s) · phone {ph or '—'} · "
            f"state {int(manifold.states_.labels_[i])} · {CLASS_LABELS[cls] if cls >= 0 else 'no step'}")
