"""Sparse lip markers drawn as lips: an interpolated outer lip contour and a tube around it.

Articulographs and small marker sets give 3 to 20 points on the lips (upper lip,
lower lip, the corners, ...). Drawn as dots they do not look like a mouth.
:class:`LipContour` orders the lip points once around the mouth (by angle in their
best-fit plane on a reference frame), adds the missing mouth corner by mirroring the
known one across the mid-sagittal plane (the plane through the upper-lower lip line
normal to the coordinate axis the corner lies along) when only one is measured, and per frame
interpolates a closed periodic cubic spline through them (chord-length parameter)
and sweeps a tube of ``n_sides`` around it. The topology is fixed, so frames animate
by moving vertices.
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np

from engine.constraints import Interval, validate_params
from engine.estimator import Estimator, check_is_fitted

__all__ = ["LipContour", "mesh_geometry", "MIN_POINTS", "MAX_POINTS"]

MIN_POINTS, MAX_POINTS = 3, 20
_LIP_ROLES = ("upper_lip", "lower_lip", "left_corner", "right_corner", "lip")


def _as_points(P, name="points"):
    P = np.asarray(P, dtype=np.float64)
    if P.ndim == 1:
        if P.size % 3:
            raise ValueError(f"{name}: a flat frame needs 3 coordinates per point, got {P.size} values")
        P = P.reshape(-1, 3)
    if P.ndim not in (2, 3) or P.shape[-1] != 3:
        raise ValueError(f"{name} must be (V, 3) or (n, V, 3), got shape {P.shape}")
    return P


class LipContour(Estimator):
    """Closed outer lip contour through sparse lip points, and a tube mesh around it.

    Parameters
    ----------
    n_samples : int, default=48
        Points along the interpolated contour.
    n_sides : int, default=8
        Sides of the tube's cross-section.
    radius : float or None, default=None
        Tube radius in the data's units (default: 4% of the reference contour's extent).

    Attributes
    ----------
    lip_points_ : ndarray of shape (L,) int
        Indices of the points on the contour, in contour order.
    mirrored_ : int or None
        Position in the contour of the mirrored (estimated) corner, or None.
    mirror_of_ : int or None
        Point index of the measured corner that is mirrored.
    axis_ : tuple of (ndarray, ndarray) or None
        Point index sets of the upper and lower lip whose centroids define the mirror line.
    lateral_ : int or None
        Coordinate axis (0, 1, 2) taken as lateral when mirroring a corner.
    radius_ : float
    faces_ : ndarray of shape (n_samples * n_sides * 2, 3) int
        Triangles of the tube.
    """

    _parameter_constraints = {
        "n_samples": [Interval(Integral, 8, None, closed="left")],
        "n_sides": [Interval(Integral, 3, None, closed="left")],
        "radius": [Interval(Real, 0, None, closed="neither"), None],
    }

    def __init__(self, *, n_samples=48, n_sides=8, radius=None):
        self.n_samples = n_samples
        self.n_sides = n_sides
        self.radius = radius

    def fit(self, points, roles=None):
        """Choose and order the lip points on a reference frame (e.g. the mean frame).

        Parameters
        ----------
        points : ndarray of shape (V, 3)
        roles : sequence of str or None
            One role per point (:data:`engine.recordings.layouts.ROLES`); points with lip roles form
            the contour. Without roles every point does.

        Returns
        -------
        self

        Raises
        ------
        ValueError
            Fewer than 3 or more than 20 lip points (a mesh should be drawn as a mesh).
        """
        validate_params(self)
        P = _as_points(points)
        if P.ndim != 2:
            raise ValueError(f"fit takes one reference frame (V, 3), got shape {P.shape}")
        V = len(P)
        if roles is not None and len(roles) != V:
            raise ValueError(f"{len(roles)} roles for {V} points; give one role per point")
        idx = [i for i in range(V) if roles is None or roles[i] in _LIP_ROLES]
        self.mirrored_ = self.mirror_of_ = self.axis_ = self.lateral_ = None
        if roles is not None:
            up = [i for i in idx if roles[i] == "upper_lip"]
            lo = [i for i in idx if roles[i] == "lower_lip"]
            corners = [i for i in idx if roles[i] in ("left_corner", "right_corner")]
            if up and lo and len(corners) == 1:
                self.axis_ = (np.array(up), np.array(lo))
                self.mirror_of_ = corners[0]
        n_lip = len(idx) + (self.mirror_of_ is not None)
        if not MIN_POINTS + 1 <= n_lip <= MAX_POINTS:
            raise ValueError(f"{n_lip} lip points (with an estimated corner); a contour needs "
                             f"{MIN_POINTS + 1} to {MAX_POINTS} (upper and lower lip and a corner at least)")
        Q = self._with_mirror(P[None], np.array(idx))[0]
        c = Q.mean(axis=0)
        _, _, Vt = np.linalg.svd(Q - c)
        ang = np.arctan2((Q - c) @ Vt[1], (Q - c) @ Vt[0])
        order = np.argsort(ang)
        ids = np.r_[idx, -1] if self.mirror_of_ is not None else np.array(idx)
        self.lip_points_ = ids[order].astype(np.int64)
        self.mirrored_ = int(np.flatnonzero(self.lip_points_ == -1)[0]) if self.mirror_of_ is not None else None
        ext = float(np.ptp(Q, axis=0).max())
        self.radius_ = float(self.radius) if self.radius is not None else 0.04 * ext
        self.faces_ = self._faces()
        return self

    def _with_mirror(self, P, idx):
        """(n, L', 3): the chosen points, plus the mirrored corner last when one is missing."""
        Q = P[:, idx]
        if self.mirror_of_ is None:
            return Q
        up, lo = self.axis_
        a = P[:, up].mean(axis=1)
        b = P[:, lo].mean(axis=1)
        d = b - a
        d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12)
        x = P[:, self.mirror_of_] - a
        if getattr(self, "lateral_", None) is None:  # fit: the coordinate axis the corner lies along
            perp = x[0] - (x[0] @ d[0]) * d[0]
            self.lateral_ = int(np.argmax(np.abs(perp)))
        n = np.zeros_like(d)
        n[:, self.lateral_] = 1.0
        n -= np.einsum("ni,ni->n", n, d)[:, None] * d  # normal of the mid-sagittal plane, which holds the lip line
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        mirrored = P[:, self.mirror_of_] - 2 * np.einsum("ni,ni->n", x, n)[:, None] * n
        return np.concatenate([Q, mirrored[:, None]], axis=1)

    def contour(self, points) -> np.ndarray:
        """The interpolated closed contour: (V, 3) -> (n_samples, 3), or (n, V, 3) -> (n, n_samples, 3)."""
        check_is_fitted(self, "lip_points_")
        P = _as_points(points)
        single = P.ndim == 2
        P = P[None] if single else P
        from scipy.interpolate import CubicSpline

        ids = self.lip_points_
        real = ids[ids >= 0]
        Q = self._with_mirror(P, np.sort(real))  # sorted real points, mirror last
        pos = {int(i): k for k, i in enumerate(np.sort(real))}
        order = [pos[int(i)] if i >= 0 else Q.shape[1] - 1 for i in ids]
        Q = Q[:, order]
        out = np.empty((len(Q), int(self.n_samples), 3))
        for f, loop in enumerate(Q):
            closed = np.vstack([loop, loop[:1]])
            seg = np.linalg.norm(np.diff(closed, axis=0), axis=1)
            t = np.r_[0, np.cumsum(np.maximum(seg, 1e-9 * (seg.max() + 1e-12)))]
            cs = CubicSpline(t, closed, bc_type="periodic", axis=0)
            out[f] = cs(np.linspace(0, t[-1], int(self.n_samples), endpoint=False))
        return out[0] if single else out

    def transform(self, points) -> np.ndarray:
        """Tube vertices: (V, 3) -> (n_samples * n_sides, 3), or (n, V, 3) -> (n, n_samples * n_sides, 3)."""
        C = self.contour(points)
        single = C.ndim == 2
        C = C[None] if single else C
        T = np.roll(C, -1, axis=1) - np.roll(C, 1, axis=1)
        T /= np.maximum(np.linalg.norm(T, axis=2, keepdims=True), 1e-12)
        c = C.mean(axis=1, keepdims=True)
        R = C - c  # outward in the lip plane
        N1 = R - np.einsum("nki,nki->nk", R, T)[..., None] * T
        N1 /= np.maximum(np.linalg.norm(N1, axis=2, keepdims=True), 1e-12)
        N2 = np.cross(T, N1)
        th = 2 * np.pi * np.arange(int(self.n_sides)) / int(self.n_sides)
        ring = (np.cos(th)[None, None, :, None] * N1[:, :, None] + np.sin(th)[None, None, :, None] * N2[:, :, None])
        Vx = C[:, :, None] + self.radius_ * ring  # (n, S, sides, 3)
        Vx = Vx.reshape(len(C), -1, 3).astype(np.float32)
        return Vx[0] if single else Vx

    def _faces(self):
        S, K = int(self.n_samples), int(self.n_sides)
        i, j = np.meshgrid(np.arange(S), np.arange(K), indexing="ij")
        a = i * K + j
        b = ((i + 1) % S) * K + j
        c = ((i + 1) % S) * K + (j + 1) % K
        d = i * K + (j + 1) % K
        return np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])


def mesh_geometry(frames, corpus, *, sensors: bool = False):
    """What to write as a mesh sequence for ``frames`` of ``corpus``: ``(points, faces, note)``.

    A corpus with faces gives its frames and faces. Sparse markers with 3 to 20 lip
    points (by ``point_roles``) give a contour tube per frame (:class:`LipContour`,
    fitted on the corpus's mean frame) and its triangles, with a note saying so;
    anything else gives bare points (faces None).

    With ``sensors=True`` a fourth item, ``labels``, names the measured sensors:
    a list of (sensor name, vertex index). For a contour tube each lip sensor on the
    contour is appended as one extra vertex at its measured position (after the tube's
    vertices, which no face uses); for bare points every point is its own sensor. A
    mesh corpus (faces) or unnamed points give ``[]``.

    Parameters
    ----------
    frames : ndarray of shape (n, dims * V)
    corpus : Corpus

    Returns
    -------
    points : ndarray of shape (n, dims * V) or (n, M, 3)
    faces : ndarray of shape (F, 3) or None
    note : str or None
    """
    from engine.recordings.corpus import frame_points

    names = corpus.point_names

    def bare():
        labels = [] if corpus.faces is not None or not names else [(str(n), i) for i, n in enumerate(names)]
        return (frames, corpus.faces, None) + ((labels,) if sensors else ())

    if corpus.faces is not None or corpus.point_roles is None:
        return bare()
    try:
        lc = LipContour().fit(frame_points(corpus.frames.mean(axis=0), corpus.dims), corpus.point_roles)
    except ValueError:
        return bare()
    P = frame_points(np.asarray(frames), corpus.dims)
    V = lc.transform(P)
    real = [int(i) for i in lc.lip_points_ if i >= 0]
    used = [names[i] if names else str(i) for i in real]
    note = (f"lip contour tube through {', '.join(used)}"
            f"{' and a mirrored corner' if lc.mirrored_ is not None else ''} ({V.shape[1]} vertices)")
    if not sensors:
        return V, lc.faces_, note
    n_tube = V.shape[1]
    V = np.concatenate([V, P[:, real].astype(V.dtype)], axis=1)
    note = note[:note.rindex("(")] + f"({n_tube} vertices, then the {len(real)} labelled sensors)"
    return V, lc.faces_, note, [(name, n_tube + k) for k, name in enumerate(used)]
