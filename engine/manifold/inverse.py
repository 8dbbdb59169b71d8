"""Inverse map Y -> X: barycentric interpolation over a Delaunay tetrahedralisation (paper 4.2).

There is no closed-form map back from the embedding, because Y is built from
distances only. The paper tetrahedralises F^y (first 3 dims) and maps a point
inside the tetrahedron Delta_ijkl to the barycentric combination of F^x at its four
vertices, the weights being ratios of sub-volumes. scipy's simplex ``transform``
gives the same weights (barycentric coordinates are exactly those volume ratios).

Details the paper leaves open, fixed here:

* **Duplicates.** Frames with identical F^y (first ``n_dims`` coordinates) become one
  vertex whose value is the mean of their F^x; when their F^x agree (as they must
  when the full F^y agree) that is exactly each frame's own F^x.
  ``duplicate_spread_`` reports the largest disagreement.
* **Every training frame maps to its own F^x.** Qhull may leave near-coincident
  points out of the triangulation ("coplanar" points); a query equal to a training
  point (within ``1e-9`` of the data's extent) therefore returns that point's value
  directly, so the map reproduces every training frame to numerical precision.
* **Outside the hull** (and inside simplices Qhull left degenerate): the point is
  mapped through the nearest simplex -- among the simplices around its 8 nearest
  vertices, the one whose smallest barycentric coordinate is largest -- with its
  weights clipped to >= 0 and renormalised. Never zeros; ``transform(...,
  return_outside=True)`` says which points were outside the hull.
* **Degenerate input.** If F^y spans fewer than ``n_dims`` affine dimensions the
  map works in the subspace they span (a segment in 1-D, a single value in 0-D).
* **Saving.** Fitted attributes are arrays only; the triangulation is rebuilt from
  ``points_`` on first use after loading (Qhull is deterministic for the same input
  and options).
* **Cold start.** scipy computes the barycentric transform of every simplex (one small
  LAPACK factorisation each, ~188k of them on the default talker) the first time a
  point is located. Under a loaded OpenBLAS that took 10-60 s. The transforms are
  computed here instead, all at once, by closed-form 2x2 / 3x3 inverses in numpy
  (``barycentric_transforms``), and handed to the triangulation before its first use.
"""
from __future__ import annotations

from numbers import Integral

import numpy as np
from scipy.spatial import ConvexHull, Delaunay, cKDTree

from engine.constraints import Interval, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.threads import single_blas_thread

__all__ = ["InverseMap", "barycentric_transforms", "delaunay_at"]

#: Qhull options: scipy's defaults for <= 4-D ("Qt" is always added by scipy)
QHULL_OPTIONS = "Qbb Qc Qz Q12"
#: relative tolerance (of the data's extent) for "same point" and "inside"
_REL_TOL = 1e-9
#: nearest vertices whose simplices are searched for points Qhull cannot locate
_N_NEAREST = 8
#: simplices whose reciprocal condition number is below this are degenerate (scipy's limit)
_RCOND_LIMIT = 1000 * np.finfo(np.float64).eps


def barycentric_transforms(points, simplices):
    """Barycentric transforms of all simplices at once, as scipy's ``Delaunay.transform``.

    For simplex ``s`` with vertices ``v_0 .. v_r``, ``T[s, :r]`` is the inverse of the
    matrix whose columns are ``v_j - v_r`` and ``T[s, r] = v_r``, so the barycentric
    coordinates of ``x`` are ``c = T[s, :r] @ (x - T[s, r])`` and ``1 - sum(c)``.
    Simplices whose reciprocal 1-norm condition number is below ``1000 * eps`` get NaN,
    as scipy marks them.

    Parameters
    ----------
    points : ndarray of shape (n_points, r)
    simplices : ndarray of shape (n_simplices, r + 1), int

    Returns
    -------
    T : ndarray of shape (n_simplices, r + 1, r), float64
    """
    P = np.asarray(points, dtype=np.float64)
    S = np.asarray(simplices)
    r = P.shape[1]
    if S.ndim != 2 or S.shape[1] != r + 1:
        raise ValueError(f"simplices must be (n, {r + 1}) for {r}-D points, got shape {S.shape}")
    V = P[S]  # (n, r+1, r)
    last = V[:, r, :]
    A = np.swapaxes(V[:, :r, :] - last[:, None, :], 1, 2)  # columns v_j - v_r
    if r == 2:
        a, b, c, d = A[:, 0, 0], A[:, 0, 1], A[:, 1, 0], A[:, 1, 1]
        det = a * d - b * c
        adj = np.stack([np.stack([d, -b], -1), np.stack([-c, a], -1)], 1)
    elif r == 3:
        c0, c1, c2 = A[:, :, 0], A[:, :, 1], A[:, :, 2]
        # rows of the adjugate are the cross products of pairs of columns
        adj = np.stack([np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)], 1)
        det = np.einsum("ij,ij->i", c0, adj[:, 0])
    else:
        det = np.linalg.det(A)
        adj = None
    with np.errstate(divide="ignore", invalid="ignore"):
        if adj is not None:
            inv = adj / det[:, None, None]
        else:
            ok = det != 0
            inv = np.full_like(A, np.nan)
            inv[ok] = np.linalg.inv(A[ok])
        rcond = 1.0 / (np.abs(A).sum(axis=1).max(axis=1) * np.abs(inv).sum(axis=1).max(axis=1))
    bad = ~(np.isfinite(rcond) & (rcond >= _RCOND_LIMIT) & (det != 0))
    T = np.empty((S.shape[0], r + 1, r), dtype=np.float64)
    T[:, :r, :] = inv
    T[:, r, :] = last
    T[bad] = np.nan
    return T


class InverseMap(Estimator):
    """Piecewise-linear map from the embedding Y back to the shape space X (or to frames).

    Parameters
    ----------
    n_dims : int, default=3
        Leading coordinates of F^y that are tetrahedralised (the paper: 3).

    Attributes
    ----------
    origin_ : ndarray of shape (n_dims,)
        Centre of the fitted points.
    basis_ : ndarray of shape (n_dims, ``rank_``)
        Orthonormal basis of the affine subspace the points span (identity when they
        span all ``n_dims`` dimensions).
    rank_ : int
        Affine dimension of the fitted points (``n_dims`` unless degenerate).
    points_ : ndarray of shape (n_unique, ``rank_``), float64
        Distinct fitted points in subspace coordinates.
    values_ : ndarray of shape (n_unique, m)
        Value (F^x or F) at each distinct point.
    point_index_ : ndarray of shape (n_samples,)
        Row of ``points_`` of every fitted sample.
    simplices_ : ndarray of shape (n_simplices, ``rank_`` + 1), int32
        Vertex indices (rows of ``points_``) of the triangulation (empty when ``rank_ < 2``).
    n_duplicates_ : int
        Samples that shared their point with an earlier sample.
    duplicate_spread_ : float
        Largest distance between a duplicate sample's value and its vertex value.
    n_dropped_ : int
        Distinct points Qhull did not use as vertices (served by exact lookup).
    tolerance_ : float
        Distance below which a query counts as a fitted point or as inside the hull.
    """

    _parameter_constraints = {"n_dims": [Interval(Integral, 1, None, closed="left")]}

    def __init__(self, *, n_dims=3):
        self.n_dims = n_dims

    # ------------------------------------------------------------------ fitting
    def fit(self, Fy, Fx):
        """Triangulate ``Fy[:, :n_dims]`` and attach ``Fx``.

        Parameters
        ----------
        Fy : ndarray of shape (N, k), k >= n_dims
            Embedding coordinates of the training frames.
        Fx : ndarray of shape (N, m)
            Values to interpolate (shape coordinates F^x, or the frames F).

        Returns
        -------
        self
        """
        validate_params(self)
        d = int(self.n_dims)
        Y = self._check_Y(Fy, d, what="Fy")
        V = np.asarray(Fx)
        if V.ndim == 1:
            V = V[:, None]
        if V.ndim != 2 or V.shape[0] != Y.shape[0]:
            raise ValueError(f"Fx must be (N, m) with N = {Y.shape[0]} rows like Fy, got shape {V.shape}")
        if V.shape[0] == 0:
            raise ValueError("cannot fit an inverse map to zero frames")
        if not np.isfinite(V).all():
            bad = int(np.argwhere(~np.isfinite(V))[0, 0])
            raise ValueError(f"Fx row {bad} holds NaN or inf")
        out_dtype = V.dtype if V.dtype in (np.float32, np.float64) else np.float64

        uniq, first, inverse = np.unique(Y, axis=0, return_index=True, return_inverse=True)
        inverse = inverse.reshape(-1)
        n_u = uniq.shape[0]
        counts = np.bincount(inverse, minlength=n_u)
        sums = np.zeros((n_u, V.shape[1]), dtype=np.float64)
        np.add.at(sums, inverse, V.astype(np.float64))
        vals = sums / counts[:, None]
        spread = 0.0
        if n_u < Y.shape[0]:
            dup = counts[inverse] > 1
            spread = float(np.linalg.norm(V[dup].astype(np.float64) - vals[inverse[dup]], axis=1).max())

        origin = uniq.mean(axis=0)
        C = uniq - origin
        extent = float(np.abs(C).max()) if C.size else 0.0
        tol = _REL_TOL * max(extent, 1e-300)
        if n_u > 1:
            _, s, Vt = np.linalg.svd(C, full_matrices=False)
            rank = int((s > 1e-9 * s[0]).sum()) if s[0] > 0 else 0
        else:
            rank, Vt = 0, np.eye(d)
        basis = np.eye(d) if rank == d else Vt[:rank].T.copy()
        P = C @ basis  # (n_u, rank)
        if rank >= 2 and n_u < rank + 1:
            raise ValueError(f"{n_u} distinct points cannot span {rank} dimensions")

        self.origin_ = origin
        self.basis_ = basis
        self.rank_ = rank
        self.points_ = np.ascontiguousarray(P)
        self.values_ = vals.astype(out_dtype)
        self.point_index_ = inverse.astype(np.int64)
        self.n_duplicates_ = int(Y.shape[0] - n_u)
        self.duplicate_spread_ = spread
        self.tolerance_ = tol
        self._reset_cache()
        if rank >= 2:
            tri = self._triangulation()
            self.simplices_ = tri.simplices.astype(np.int32)
            used = np.zeros(n_u, dtype=bool)
            used[tri.simplices.ravel()] = True
            self.n_dropped_ = int((~used).sum())
        else:
            self.simplices_ = np.zeros((0, rank + 1), dtype=np.int32)
            self.n_dropped_ = 0
        return self

    @staticmethod
    def _check_Y(Y, d, *, what="Y"):
        Y = np.asarray(Y, dtype=np.float64)
        if Y.ndim == 1 and d == 1:
            Y = Y[:, None]
        if Y.ndim != 2 or Y.shape[1] < d:
            raise ValueError(f"{what} must be 2-D with at least n_dims={d} columns, got shape {Y.shape}")
        Y = Y[:, :d]
        if not np.isfinite(Y).all():
            bad = int(np.argwhere(~np.isfinite(Y))[0, 0])
            raise ValueError(f"{what} row {bad} holds NaN or inf")
        return Y

    # ------------------------------------------------------------ lazy caches
    def _reset_cache(self):
        self._tri = None
        self._tree = None
        self._hull = None
        self._incidence = None

    def _triangulation(self) -> Delaunay:
        if getattr(self, "_tri", None) is None:
            tri = Delaunay(self.points_, qhull_options=QHULL_OPTIONS)
            # scipy would otherwise factorise every simplex one by one on first use
            tri._transform = barycentric_transforms(tri.points, tri.simplices)
            self._tri = tri
        return self._tri

    def _kdtree(self) -> cKDTree:
        if getattr(self, "_tree", None) is None:
            self._tree = cKDTree(self.points_)
        return self._tree

    def _vertex_simplices(self):
        """CSR incidence vertex -> simplices: (indptr (n_u+1,), simplex ids)."""
        if getattr(self, "_incidence", None) is None:
            S = self._triangulation().simplices
            flat = S.ravel()
            order = np.argsort(flat, kind="stable")
            indptr = np.zeros(self.points_.shape[0] + 1, dtype=np.int64)
            np.cumsum(np.bincount(flat, minlength=self.points_.shape[0]), out=indptr[1:])
            self._incidence = (indptr, order // S.shape[1])
        return self._incidence

    def _outside_hull(self, P):
        if getattr(self, "_hull", None) is None:
            self._hull = ConvexHull(self.points_).equations
        eq = self._hull
        return (P @ eq[:, :-1].T + eq[:, -1]).max(axis=1) > self.tolerance_

    # ---------------------------------------------------------------- mapping
    @single_blas_thread
    def transform(self, Y, *, return_outside=False):
        """Map embedding points to values.

        Parameters
        ----------
        Y : ndarray of shape (n, k), k >= n_dims
            Points in the embedding; only the first ``n_dims`` columns are used.
        return_outside : bool, default=False
            Also return which points lay outside the convex hull of the fitted points.

        Returns
        -------
        X : ndarray of shape (n, m)
            Interpolated values (dtype of the fitted values).
        outside : ndarray of shape (n,), bool
            Only with ``return_outside=True``.
        """
        check_is_fitted(self, "values_")
        Y = self._check_Y(Y, int(self.n_dims))
        P = (Y - self.origin_) @ self.basis_
        n = P.shape[0]
        out = np.empty((n, self.values_.shape[1]), dtype=np.float64)
        outside = np.zeros(n, dtype=bool)
        if n == 0:
            return (out.astype(self.values_.dtype), outside) if return_outside else out.astype(self.values_.dtype)
        if self.rank_ == 0:
            out[:] = self.values_[0]
            outside = np.linalg.norm(Y - self.origin_, axis=1) > self.tolerance_
        elif self.rank_ == 1:
            out, outside = self._transform_1d(P[:, 0])
        else:
            out, outside = self._transform_nd(P)
        # points off the subspace of a degenerate fit are outside too
        if self.rank_ < int(self.n_dims) and self.rank_ > 0:
            resid = (Y - self.origin_) - P @ self.basis_.T
            outside |= np.linalg.norm(resid, axis=1) > self.tolerance_
        # exact lookup: a query at a fitted point returns that point's own value
        dist, idx = self._kdtree().query(P, k=1, distance_upper_bound=self.tolerance_)
        hit = np.isfinite(dist)
        out[hit] = self.values_[idx[hit]]
        out = out.astype(self.values_.dtype, copy=False)
        return (out, outside) if return_outside else out

    def _transform_1d(self, p):
        x = self.points_[:, 0]
        order = np.argsort(x)
        xs, vs = x[order], self.values_[order].astype(np.float64)
        pc = np.clip(p, xs[0], xs[-1])
        j = np.clip(np.searchsorted(xs, pc, side="right") - 1, 0, len(xs) - 2)
        w = (pc - xs[j]) / (xs[j + 1] - xs[j])
        out = (1 - w)[:, None] * vs[j] + w[:, None] * vs[j + 1]
        outside = (p < xs[0] - self.tolerance_) | (p > xs[-1] + self.tolerance_)
        return out, outside

    def _transform_nd(self, P):
        tri = self._triangulation()
        r = self.rank_
        s = tri.find_simplex(P)
        n = P.shape[0]
        W = np.zeros((n, r + 1))
        verts = np.zeros((n, r + 1), dtype=np.int64)
        found = s >= 0
        if found.any():
            T = tri.transform[s[found]]
            b = np.einsum("nij,nj->ni", T[:, :r, :], P[found] - T[:, r, :])
            W[found] = np.column_stack([b, 1.0 - b.sum(axis=1)])
            verts[found] = tri.simplices[s[found]]
        lost = np.flatnonzero(~found)
        outside = np.zeros(n, dtype=bool)
        if lost.size:
            w_l, v_l = self._nearest_simplex(P[lost])
            W[lost], verts[lost] = w_l, v_l
            outside[lost] = self._outside_hull(P[lost])
        out = np.einsum("nk,nkm->nm", W, self.values_[verts].astype(np.float64))
        return out, outside

    def _nearest_simplex(self, P):
        """Clamped barycentric weights in the best simplex around each point's nearest vertices."""
        tri = self._triangulation()
        r = self.rank_
        indptr, simp = self._vertex_simplices()
        k = min(_N_NEAREST, self.points_.shape[0])
        _, nn = self._kdtree().query(P, k=k)
        nn = nn.reshape(P.shape[0], k)
        W = np.zeros((P.shape[0], r + 1))
        V = np.zeros((P.shape[0], r + 1), dtype=np.int64)
        Tall = tri.transform
        for i in range(P.shape[0]):
            cand = np.unique(np.concatenate([simp[indptr[v]:indptr[v + 1]] for v in nn[i]]))
            T = Tall[cand]
            ok = np.isfinite(T).all(axis=(1, 2))
            if not ok.any():  # every nearby simplex degenerate: nearest vertex value
                W[i, 0], V[i, 0] = 1.0, nn[i, 0]
                continue
            cand, T = cand[ok], T[ok]
            b = np.einsum("cij,j->ci", T[:, :r, :], P[i]) - np.einsum("cij,cj->ci", T[:, :r, :], T[:, r, :])
            c = np.column_stack([b, 1.0 - b.sum(axis=1)])
            best = int(np.argmax(c.min(axis=1)))
            w = np.clip(c[best], 0.0, None)
            W[i] = w / w.sum()
            V[i] = tri.simplices[cand[best]]
        return W, V


def _circumspheres(V):
    """Centres (n, 3) and squared radii (n,) of the circumspheres of tetrahedra V (n, 4, 3)."""
    A = 2.0 * (V[:, 1:] - V[:, :1])  # (n, 3, 3)
    b = (V[:, 1:] ** 2).sum(axis=2) - (V[:, :1] ** 2).sum(axis=2)
    c = np.linalg.solve(A, b[..., None])[..., 0]
    return c, ((V[:, 0] - c) ** 2).sum(axis=1)


@single_blas_thread
def delaunay_at(Fy, Fx, queries, *, tree=None, n_neighbors: int = 32, max_neighbors: int = 4096):
    """The Delaunay inverse map of ``(Fy, Fx)`` at a few query points, from local triangulations.

    :class:`InverseMap` tetrahedralises every frame; to map a few points (a manifold's
    state centroids) that costs minutes and gigabytes at a million frames. The
    tetrahedron of the Delaunay triangulation that holds a query is determined by the
    frames near it: the query's nearest frames are triangulated, the tetrahedron holding
    the query is taken when its circumsphere holds no other frame of the whole set (then
    it is a tetrahedron of the whole set's triangulation too), otherwise the
    neighbourhood grows by the frames found inside. The value is the barycentric
    combination of its vertices' values (a vertex shared by duplicate frames takes their
    mean, as :class:`InverseMap` does), so it equals ``InverseMap(n_dims=3).fit(Fy,
    Fx).transform(queries)`` up to round-off wherever a query lies inside the frames'
    hull and the points are in general position.

    Parameters
    ----------
    Fy : ndarray of shape (N, >=3)
        The frames in the embedding (Y1-3 are used).
    Fx : ndarray of shape (N, m)
        Their values.
    queries : ndarray of shape (n, >=3)
    tree : scipy.spatial.cKDTree, optional
        Of ``Fy[:, :3]`` in float64 (built when not given).
    n_neighbors, max_neighbors : int
        First and largest neighbourhood triangulated.

    Returns
    -------
    ndarray of shape (n, m), float64
        NaN rows where no tetrahedron could be found (a query outside the hull, or a
        degenerate neighbourhood): map those with :class:`InverseMap`.
    """
    Y = np.ascontiguousarray(np.asarray(Fy)[:, :3], dtype=np.float64)
    Q = np.asarray(queries, dtype=np.float64)[:, :3]
    tree = cKDTree(Y) if tree is None else tree
    N, out = Y.shape[0], np.full((Q.shape[0], np.asarray(Fx).shape[1]), np.nan)
    extent = float(np.abs(Y - Y.mean(axis=0)).max()) if N else 0.0
    tol = _REL_TOL * max(extent, 1e-300)
    for i, q in enumerate(Q):
        dist, idx = tree.query(q, k=min(n_neighbors, N))
        idx = np.atleast_1d(idx)
        if np.atleast_1d(dist)[0] <= tol:  # a query at a frame: that frame's value (duplicates: their mean)
            out[i] = np.asarray(Fx)[tree.query_ball_point(Y[idx[0]], 0.0)].astype(np.float64).mean(axis=0)
            continue
        while True:
            try:
                tri = Delaunay(Y[idx], qhull_options=QHULL_OPTIONS)
                s = int(tri.find_simplex(q))
            except Exception:  # noqa: BLE001 - Qhull refuses a flat neighbourhood: grow it
                s = -1
            if s >= 0:
                verts = idx[tri.simplices[s]]
                V = Y[verts][None]
                with np.errstate(all="ignore"):
                    c, r2 = _circumspheres(V)
                if np.isfinite(r2).all():
                    inside = np.asarray(tree.query_ball_point(c[0], np.sqrt(r2[0]) * (1 - 1e-9)), dtype=np.int64)
                    extra = np.setdiff1d(inside, idx)
                    same = np.isin(inside, verts) | (((Y[inside] - c[0]) ** 2).sum(axis=1) >= r2[0] * (1 - 1e-9))
                    if same.all():
                        T = barycentric_transforms(Y[verts], np.arange(4)[None])[0]
                        b = T[:3] @ (q - T[3])
                        w = np.r_[b, 1.0 - b.sum()]
                        vals = np.stack([
                            np.asarray(Fx)[tree.query_ball_point(Y[v], 0.0)].astype(np.float64).mean(axis=0)
                            for v in verts])
                        out[i] = w @ vals
                        break
                    if extra.size and idx.size < max_neighbors:  # frames inside the sphere: triangulate with them
                        idx = np.concatenate([idx, extra])
                        continue
            if idx.size >= min(max_neighbors, N):
                break  # outside the hull or degenerate: left to InverseMap
            _d, idx = tree.query(q, k=min(2 * idx.size, max_neighbors, N))
            idx = np.atleast_1d(idx)
    return out
