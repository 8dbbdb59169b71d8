"""Tangent space of the manifold and the four movement classes (paper section 3.2).

The manifold is symmetric about a **zero-velocity plane** with the opening half of
each speech cycle on one side and the closing half on the other. Its unit normal is
the global velocity direction V; inside it, the global shape direction S orders lip
shapes by opening. Each frame also gets a **local frame** from its neighbourhood in
F^y: the direction s_i along which opening (F^x_1) grows fastest, the direction v_i
along which opening velocity (F^x'_1) grows fastest (local least-squares gradients;
their span is the local tangent plane) and the local orientation s_i x v_i (the
direction along which neither changes: the manifold's thickness). See
:class:`TangentFrames` for why the gradients are not confined to the neighbourhood's
PCA plane, and ``local_plane="pca"`` for that variant.

With the forward step d_i = F^y_{i+1} - F^y_i inside an utterance (the paper writes
z_i = F^y_i - F^y_{i+1}; we use the forward step so that the signs read directly):

* opening       iff d_i . s_i > 0,
* accelerating  iff sign(d_i . v_i) == sign(d_i . s_i) (the magnitude of the opening
  velocity grows: it grows while opening, or falls further below zero while closing).

Sign convention: **+F^x_1 is opening** (``engine.shape`` orients component 1 so that
its positive direction spreads the lip points apart). Nothing here can check that;
inputs whose first shape component points toward closing, or is not opening at all
(a rigid shift, tongue movement), give wrong classes. When the lip aperture is known
(the corpus names upper and lower lip points), pass it as ``opening`` to ``fit``: it
then defines opening instead (:class:`engine.manifold.Manifold` does so).
"""
from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.neighbors import NearestNeighbors
from sklearn.utils.validation import check_is_fitted

from engine.dynamics import check_bounds

__all__ = ["TangentFrames", "CLASS_NAMES", "NO_STEP", "local_frames_block"]

#: names of ``classes_`` 0..3
CLASS_NAMES = ("opening/accelerating", "opening/decelerating", "closing/accelerating", "closing/decelerating")
#: class of a frame with no forward step (the last frame of each utterance)
NO_STEP = -1

_CHUNK = 8192
#: a zero-velocity set whose smallest two spreads are closer than this ratio is a line, not a plane
_PLANAR_RATIO = 0.5
#: ridge of the local gradient regressions, relative to the neighbourhood's total spread
_RIDGE = 1e-4


def _finite_2d(name, a, n_rows=None, min_cols=1):
    a = np.asarray(a)
    if a.ndim != 2:
        raise ValueError(f"{name} must be a 2-D (frames, dims) array, got shape {a.shape}")
    if n_rows is not None and a.shape[0] != n_rows:
        raise ValueError(f"{name} has {a.shape[0]} frames but F^y has {n_rows}; pass arrays of the same corpus")
    if a.shape[1] < min_cols:
        raise ValueError(f"{name} needs at least {min_cols} columns, got {a.shape[1]}")
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        raise ValueError(f"{name} holds NaN or infinite values (first at frame {int(np.flatnonzero(bad)[0])}); "
                         f"remove or repair those frames")
    return a


def _unit(x, axis=-1):
    n = np.linalg.norm(x, axis=axis, keepdims=True)
    return x / np.where(n > 0, n, 1.0), n[..., 0]


def _in_plane_gradient(C, f, ridge=1e-10):
    """Least-squares gradient of ``f`` (n,) over in-plane coordinates ``C`` (n, 2), centred."""
    C = C - C.mean(axis=0)
    f = f - f.mean()
    CtC = C.T @ C
    CtC += (ridge * np.trace(CtC) + 1e-300) * np.eye(2)
    return np.linalg.solve(CtC, C.T @ f)


def local_frames_block(start, stop, nn, Y, x1, v1, S, V, opts):
    """Local frames s_i, v_i, s_i x v_i of frames ``start:stop`` (see :class:`TangentFrames`, Notes).

    Parameters
    ----------
    start, stop : int
        The block of frames.
    nn : sklearn.neighbors.NearestNeighbors
        Fitted on all of Y with ``n_neighbors + 1`` neighbours (the frame itself included).
    Y : ndarray of shape (N, 3), float32
    x1, v1 : ndarray of shape (N,)
        Opening and its velocity.
    S, V : ndarray of shape (3,)
        Global shape and velocity directions (the fallbacks).
    opts : dict
        ``in_plane`` (bool), ``tiny`` ({"x": float, "v": float}), ``y_scale`` (float).

    Returns
    -------
    s, v, normal : ndarray of shape (stop - start, 3), float32
    n_bad : int
        Frames that needed a fallback.
    """
    z = slice(start, stop)
    k = nn.n_neighbors
    in_plane, tiny, y_scale = opts["in_plane"], opts["tiny"], opts["y_scale"]
    SxV = np.cross(S, V)
    idx = nn.kneighbors(Y[z], return_distance=False)  # (B, k), self included
    P = Y[idx].astype(np.float64)
    P -= P.mean(axis=1, keepdims=True)
    w, E = np.linalg.eigh(np.einsum("bki,bkj->bij", P, P))  # ascending; E[:, :, 0] = PCA normal
    U = np.einsum("bki,bij->bkj", P, E)  # (B, k, 3) uncorrelated coordinates: U^T U = diag(w)
    tr = w.sum(axis=1)
    denom = w + (_RIDGE * tr + 1e-300)[:, None]
    flat = tr <= 1e-12 * y_scale * k  # neighbours (nearly) coincide
    out = []
    for f, key, glob in ((x1, "x", S), (v1, "v", V)):
        fk = f[idx]
        fk = fk - fk.mean(axis=1, keepdims=True)
        g = np.einsum("bki,bk->bi", U, fk) / denom  # least-squares gradient, eigen-coordinates
        if in_plane:
            g[:, 0] = 0.0
        d, dn = _unit(np.einsum("bij,bj->bi", E, g))
        bad = flat | (fk.std(axis=1) <= tiny[key]) | ~(dn > 0) | ~np.isfinite(dn)
        if bad.any():
            fb = np.broadcast_to(glob, (int(bad.sum()), 3)).copy()
            if in_plane:
                e0 = E[bad, :, 0]
                fb -= np.einsum("bi,bi->b", fb, e0)[:, None] * e0
            fb, fn = _unit(fb)
            fb[fn < 1e-3] = glob
            d[bad] = fb
        out.append((d, bad))
    (sd, sbad), (vd, vbad) = out
    c, cn = _unit(np.cross(sd, vd))
    cbad = cn < 1e-6
    if cbad.any():
        e0 = E[cbad, :, 0]
        e0 *= np.where(e0 @ SxV < 0, -1.0, 1.0)[:, None]
        c[cbad] = e0
    return (sd.astype(np.float32), vd.astype(np.float32), c.astype(np.float32), int((sbad | vbad | cbad).sum()))


class TangentFrames(BaseEstimator):
    """Zero-velocity plane, global S and V, local tangent frames and movement classes.

    Parameters
    ----------
    n_neighbors : int, default=20
        Neighbours (besides the frame itself) whose PCA in F^y gives a frame's tangent
        plane. At least 3.
    n_dims : {3, 2}, default=3
        Columns of F^y used. With 2, F^y is padded with a zero third coordinate (the
        "plane" is then a line in the Y1-Y2 plane and every local normal is +-Y3).
    zero_velocity_quantile : float, default=0.1
        Fraction of frames, those with the smallest ||F^x'||, that the zero-velocity
        plane is fitted to.
    local_plane : {"gradients", "pca"}, default="gradients"
        Where s_i and v_i live. ``"gradients"``: they are the full local gradients of
        F^x_1 and F^x'_1 in F^y, and the local tangent plane is their span.
        ``"pca"``: they are restricted to the plane of the neighbourhood's top two
        principal axes (the in-plane reading). See Notes for why the default
        differs.

    Attributes
    ----------
    plane_point_ : ndarray of shape (3,)
        Mean of the zero-velocity frames in F^y.
    plane_normal_ : ndarray of shape (3,)
        Unit normal of the zero-velocity plane = global velocity direction V, oriented
        so that the signed distance correlates positively with F^x'_1 (+V = opening).
    S_ : ndarray of shape (3,)
        Unit global shape direction: in the plane, the direction along which F^x_1 grows
        (least-squares gradient over all frames projected into the plane).
    plane_spread_ : ndarray of shape (3,)
        Eigenvalues (ascending) of the zero-velocity frames' covariance in F^y.
    s_, v_, normal_ : ndarray of shape (N, 3), float32
        Local unit shape direction, velocity direction and orientation s_i x v_i.
    step_ : ndarray of shape (N, 3), float32
        Forward steps d_i; zeros at the last frame of each utterance.
    opening_, accelerating_ : ndarray of shape (N,), bool
        False where there is no forward step.
    classes_ : ndarray of shape (N,), int8
        0 opening/accelerating, 1 opening/decelerating, 2 closing/accelerating,
        3 closing/decelerating, -1 (``NO_STEP``) at the last frame of each utterance.
    n_degenerate_ : int
        Frames whose s_i, v_i or normal needed a fallback (see Notes).
    opening_source_ : str
        What defined opening: ``"lip aperture"`` (``opening`` given to fit) or ``"F^x_1"``.

    Notes
    -----
    *Zero-velocity plane*: PCA of the slowest frames; the normal is the direction of
    least spread. When that set is a line rather than a plane (the two smallest
    spreads within a factor of 2), the normal is instead the direction, within the
    two least-spread axes, along which F^x'_1 grows (least squares over all frames).

    *Local frames*: PCA of the frame and its ``n_neighbors`` nearest neighbours in
    F^y (KD-tree) gives uncorrelated local coordinates; s_i and v_i are the
    least-squares gradients of F^x_1 and F^x'_1 over the neighbours in those
    coordinates (ridge 1e-4 of the total spread, which only damps axes of negligible
    spread), mapped back to F^y and normalised. The local neighbourhoods are not
    flat: the velocity axis is the thinnest direction of the manifold, and over 20
    neighbours the curvature of the shape axis spreads as much as velocity does, so
    the PCA plane often misses the velocity direction. Restricting the gradients to
    that plane (``local_plane="pca"``) classifies acceleration no better than about
    82% of moving frames in our checks against ground truth, the full gradients
    about 97%. With the default, the tangent plane is span(s_i, v_i) and
    s_i x v_i is the direction along which neither opening nor its velocity changes
    (the paper's "direction of thickness").

    Fallbacks, never NaN: a gradient that cannot be estimated (neighbours coincide,
    or the quantity is constant over them) is replaced by the global S (or V) —
    projected onto the PCA plane with ``local_plane="pca"``; when s_i and v_i are
    parallel the normal is the neighbourhood's least-spread axis, oriented along
    S x V. ``n_degenerate_`` counts frames that needed any fallback.

    *Classes*: a zero step (a repeated frame) is "closing" (d.s > 0 fails) and
    "accelerating" (the signs agree at 0), exactly as the rule reads.
    """

    CLASS_NAMES = CLASS_NAMES

    def __init__(self, *, n_neighbors=20, n_dims=3, zero_velocity_quantile=0.1, local_plane="gradients"):
        self.n_neighbors = n_neighbors
        self.n_dims = n_dims
        self.zero_velocity_quantile = zero_velocity_quantile
        self.local_plane = local_plane

    # ------------------------------------------------------------------ input
    def _check_params(self):
        if self.n_dims not in (2, 3):
            raise ValueError(f"n_dims must be 2 or 3 (the tangent frames live in 3-D), got {self.n_dims!r}")
        if not isinstance(self.n_neighbors, (int, np.integer)) or self.n_neighbors < 3:
            raise ValueError(f"n_neighbors must be an integer >= 3 (a tangent plane needs 3 points), "
                             f"got {self.n_neighbors!r}")
        q = self.zero_velocity_quantile
        if not (isinstance(q, (int, float, np.floating)) and 0 < q < 1):
            raise ValueError(f"zero_velocity_quantile must be in (0, 1), got {q!r}; the default is 0.1")
        if self.local_plane not in ("gradients", "pca"):
            raise ValueError(f"local_plane must be 'gradients' or 'pca', got {self.local_plane!r}")

    def _as_y3(self, Y, name="Y") -> np.ndarray:
        Y = np.asarray(Y)
        if Y.ndim == 1:
            Y = Y[None, :]
        Y = _finite_2d(name, Y, min_cols=self.n_dims)
        Y = np.asarray(Y[:, : self.n_dims], dtype=np.float32)
        if self.n_dims < 3:
            Y = np.hstack([Y, np.zeros((len(Y), 3 - self.n_dims), np.float32)])
        return np.ascontiguousarray(Y)

    # -------------------------------------------------------------------- fit
    def fit(self, Fy, Fx, Fxv, bounds, opening=None, *, executor=None):
        """Fit the plane, the global and local directions and classify every frame.

        Parameters
        ----------
        Fy : ndarray of shape (N, k >= n_dims)
            The embedding F^y.
        Fx : ndarray of shape (N, m)
            Shape coordinates F^x (column 0 = opening).
        Fxv : ndarray of shape (N, m')
            Their velocities F^x' (column 0 = opening velocity).
        bounds : ndarray of shape (U, 2)
            Utterance ``[start, stop)`` frame ranges (``Corpus.bounds``).
        opening : ndarray of shape (N,), optional
            A measured opening signal, the lip aperture (:func:`engine.kinematics.lip_aperture`).
            When given it replaces F^x_1 (and its velocity replaces F^x'_1) as the
            reference of S, V, s_i, v_i and so of the classes: "opening" then means the
            lips part, whatever the first shape component is. ``opening_source_`` says
            which was used.
        executor : object with ``map_row_blocks``, optional
            Computes the local frames one block of frames per task
            (:meth:`engine.scale.DaskExecutor.map_row_blocks`); None: in-process. Same
            result: the plane, S, V and the classes are computed here from them.

        Returns
        -------
        self
        """
        self._check_params()
        Y = self._as_y3(Fy, "F^y")
        N = Y.shape[0]
        x1 = np.asarray(_finite_2d("F^x", Fx, N)[:, 0], dtype=np.float64)
        Fxv = _finite_2d("F^x'", Fxv, N)
        v1 = np.asarray(Fxv[:, 0], dtype=np.float64)
        b = check_bounds(bounds, N)
        source = "F^x_1"
        if opening is not None:
            op = np.asarray(opening, dtype=np.float64).reshape(-1)
            if op.shape[0] != N or not np.isfinite(op).all():
                raise ValueError(f"opening must be {N} finite values (one per frame of F^y), got shape {op.shape}")
            from engine.dynamics import velocities

            x1, v1 = op, velocities(op[:, None], b)[:, 0]
            source = "lip aperture"
        k = int(self.n_neighbors)
        if N <= k:
            raise ValueError(f"n_neighbors={k} needs more than {k} frames, got {N}; lower n_neighbors")

        point, V, spread = self._zero_velocity_plane(Y, Fxv, v1)
        S = self._global_shape(Y, point, V, x1)
        s, v, nrm, n_bad = self._local_frames(Y, x1, v1, S, V, executor)

        step = np.zeros_like(Y)
        step[:-1] = Y[1:] - Y[:-1]
        has = np.ones(N, bool)
        has[b[:, 1] - 1] = False
        step[~has] = 0.0
        ds = np.einsum("ij,ij->i", step, s)
        dv = np.einsum("ij,ij->i", step, v)
        opening = (ds > 0) & has
        accel = (np.sign(dv) == np.sign(ds)) & has
        classes = (2 * (~opening) + (~accel)).astype(np.int8)
        classes[~has] = NO_STEP

        self.plane_point_, self.plane_normal_, self.S_, self.plane_spread_ = point, V, S, spread
        self.s_, self.v_, self.normal_, self.step_ = s, v, nrm, step
        self.opening_, self.accelerating_, self.classes_ = opening, accel, classes
        self.n_degenerate_ = int(n_bad)
        self.opening_source_ = source
        return self

    def _zero_velocity_plane(self, Y, Fxv, v1):
        N = len(Y)
        speed = np.linalg.norm(np.asarray(Fxv, dtype=np.float64), axis=1)
        n_low = int(min(N, max(3, np.ceil(self.zero_velocity_quantile * N))))
        low = np.argpartition(speed, n_low - 1)[:n_low]
        d = self.n_dims  # with n_dims=2 the "plane" is a line in Y1-Y2 (the padded axis is no candidate)
        P = Y[low].astype(np.float64)
        point = P.mean(axis=0)
        Pc = P[:, :d] - point[:d]
        w, E = np.linalg.eigh(Pc.T @ Pc / len(P))
        normal = E[:, 0]
        if w[1] <= 0 or w[0] > _PLANAR_RATIO * w[1]:
            # a line (or a point), not a plane: pick the normal among the two least-spread
            # axes as the direction along which opening velocity grows
            B = E[:, :2]
            g = _in_plane_gradient((Y[:, :d].astype(np.float64) - point[:d]) @ B, v1)
            if np.linalg.norm(g) > 0:
                normal = B @ (g / np.linalg.norm(g))
        normal = np.r_[normal, np.zeros(3 - d)]
        w = np.r_[np.zeros(3 - d), w]
        sd = (Y.astype(np.float64) - point) @ normal
        c = float(np.dot(sd - sd.mean(), v1 - v1.mean()))
        if c < 0 or (c == 0 and normal[np.argmax(np.abs(normal))] < 0):
            normal = -normal
        return point, normal / np.linalg.norm(normal), w

    @staticmethod
    def _global_shape(Y, point, V, x1):
        B = np.linalg.svd(V[None, :])[2][1:]  # (2, 3) orthonormal basis of the plane
        C = (Y.astype(np.float64) - point) @ B.T
        g = _in_plane_gradient(C, x1)
        if np.linalg.norm(g) == 0 or not np.isfinite(g).all():
            # opening is constant: fall back to the plane's principal axis
            w, E = np.linalg.eigh(np.cov(C.T))
            g = E[:, -1]
            if g[np.argmax(np.abs(g))] < 0:
                g = -g
        S = B.T @ g
        return S / np.linalg.norm(S)

    def _local_frames(self, Y, x1, v1, S, V, executor=None):
        N = len(Y)
        nn = NearestNeighbors(n_neighbors=int(self.n_neighbors) + 1, algorithm="kd_tree").fit(Y)
        opts = {"in_plane": self.local_plane == "pca",
                "tiny": {"x": 1e-6 * (np.std(x1) + 1e-300), "v": 1e-6 * (np.std(v1) + 1e-300)},
                "y_scale": float(np.ptp(Y, axis=0).max()) ** 2 + 1e-300}
        if executor is None:
            parts = [local_frames_block(a, min(N, a + _CHUNK), nn, Y, x1, v1, S, V, opts) for a in range(0, N, _CHUNK)]
        else:  # one task per block of frames; the fitted tree, Y, x1, v1 travel once to each worker
            parts = executor.map_row_blocks(local_frames_block, N, nn, Y, x1, v1, S, V, opts, block=_CHUNK)
        s, v, nrm = (np.concatenate([p[i] for p in parts]) for i in range(3))
        return s, v, nrm, sum(p[3] for p in parts)

    # ------------------------------------------------------------------ query
    def signed_velocity(self, Y) -> np.ndarray:
        """Signed distance of points to the zero-velocity plane (> 0: opening side).

        Parameters
        ----------
        Y : ndarray of shape (n, k >= n_dims) or (k,)

        Returns
        -------
        ndarray of shape (n,), float64
        """
        check_is_fitted(self, "plane_normal_")
        Y = self._as_y3(Y)
        return (Y.astype(np.float64) - self.plane_point_) @ self.plane_normal_

    def sv_basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(origin (3,), S (3,), V (3,)), float64: the plane point and the global shape and velocity directions.

        S is re-orthogonalised against V (they are orthogonal by construction; this only
        guards against rounding).
        """
        check_is_fitted(self, "plane_normal_")
        V = np.asarray(self.plane_normal_, dtype=np.float64)
        V = V / np.linalg.norm(V)
        S = np.asarray(self.S_, dtype=np.float64)
        S = S - (S @ V) * V
        return np.asarray(self.plane_point_, dtype=np.float64), S / np.linalg.norm(S), V

    def sv_coordinates(self, Y) -> np.ndarray:
        """Coordinates of points along the global directions (S, V) about the plane point.

        The one reading of "where a frame sits on the S and V axes": the figures (the
        S-V panels) and the per-frame table (:mod:`engine.frame_table`) both take it
        from here. In these coordinates the zero-velocity plane is the line ``v = 0``
        (``v > 0``: the opening side) and speech cycles are the paper's elliptical paths.

        Parameters
        ----------
        Y : ndarray of shape (n, k >= n_dims) or (k,)
            Points of F^y (only the first ``n_dims`` columns are used).

        Returns
        -------
        ndarray of shape (n, 2), float64
            Column 0 along S, column 1 along V (in F^y units).
        """
        o, S, V = self.sv_basis()
        d = self._as_y3(Y).astype(np.float64) - o
        return np.column_stack([d @ S, d @ V])

    def class_proportions(self) -> dict:
        """Fraction of frames (with a forward step) in each class, ``{CLASS_NAMES[c]: fraction}``."""
        check_is_fitted(self, "classes_")
        c = np.asarray(self.classes_)
        c = c[c >= 0]
        counts = np.bincount(c, minlength=len(CLASS_NAMES)).astype(np.float64)
        frac = counts / counts.sum() if counts.sum() else counts
        return {name: float(f) for name, f in zip(CLASS_NAMES, frac)}
