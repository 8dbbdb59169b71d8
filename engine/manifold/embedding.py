"""Embedding Y: PCA of the distance matrix D of the dynamic features (paper section 3.1).

``D_ij = ||G_i - G_j||``. The paper decomposes D with PCA (rows of D as
observations, centred by the mean row) and keeps the projections F^y. D is N x N, so
it is never formed: every product with D is computed block by block from G inside
a randomized range finder, keeping memory at O(N k + block N).

Methods
-------
``"pca"``  the paper's PCA of D.
``"mds"``  classical MDS / principal coordinates: eigenvectors of -1/2 J D^2 J.
``n_landmarks=L`` uses the distances to L landmark frames only (an N x L matrix,
a Nystrom-style approximation) with the same interface, for corpora too large for
N^2 work.
"""
from __future__ import annotations

import os
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from numbers import Integral

import numpy as np

from engine.constraints import Interval, StrOptions, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.manifold.shape import orthonormal_basis, thin_svd
from engine.progress import ProgressFn, report
from engine.threads import one_blas_thread

__all__ = ["Embedding", "pairwise_distance_block"]

#: bytes of one block of rows of D: 8 MiB blocks stay in the cores' caches between the GEMM
#: that forms them and the one that uses them; 96 MiB blocks took 1.1-1.4x as long for
#: the same products on the paper-scale talker (identical F^y)
_BLOCK_BYTES = 8 * 2**20


def pairwise_distance_block(A, B, B_sq=None, *, squared=False) -> np.ndarray:
    """Euclidean distances between rows of A (a, d) and B (b, d) -> (a, b) float32."""
    A = np.asarray(A, dtype=np.float32)
    B = np.asarray(B, dtype=np.float32)
    if B_sq is None:
        B_sq = np.einsum("ij,ij->i", B, B)
    A_sq = np.einsum("ij,ij->i", A, A)
    D = A @ B.T
    D *= -2.0
    D += A_sq[:, None]
    D += B_sq[None, :]
    np.maximum(D, 0.0, out=D)
    if not squared:
        np.sqrt(D, out=D)
    return D


def _augment(A, A_sq):
    """Rows [a, |a|^2, 1] so that one GEMM with [-2b, 1, |b|^2] gives squared distances."""
    n = A.shape[0]
    return np.hstack([A, A_sq[:, None], np.ones((n, 1), np.float32)]).astype(np.float32)


class _DistanceOperator:
    """Products with D (or D^2) between rows of G and a set of column points, block-wise.

    Each block of rows of D is formed by one GEMM on augmented coordinates, used and
    dropped; blocks run on a small thread pool (BLAS limited to one thread per worker).
    """

    def __init__(self, G, cols, *, squared, block, progress, stage):
        self.G = G
        self.cols = cols
        self.cols_sq = np.einsum("ij,ij->i", cols, cols)
        self._rows_aug = _augment(G, np.einsum("ij,ij->i", G, G))
        self._cols_aug_t = np.ascontiguousarray(
            np.hstack([-2.0 * cols, np.ones((cols.shape[0], 1), np.float32), self.cols_sq[:, None]]).T,
            dtype=np.float32)
        self.squared = squared
        self.block = block
        self.progress = progress
        self.stage = stage
        self.passes = 0
        self.workers = max(1, min(4, os.cpu_count() or 1))

    def block_rows(self, sl) -> np.ndarray:
        """Rows ``sl`` of D (or D^2), float32."""
        D = self._rows_aug[sl] @ self._cols_aug_t
        np.maximum(D, 0.0, out=D)
        if not self.squared:
            np.sqrt(D, out=D)
        return D

    def _map(self, fn, reduce):
        """Run ``fn`` on every block of rows; ``reduce(sl, result)`` in block order.

        At most a few blocks per worker are in flight (a sliding window) and each result
        is reduced, in block order, and dropped, so memory holds O(workers) block results,
        never one per block (with N^2/block blocks that grew as N^3), and sums are
        taken in a fixed order (results do not depend on thread timing).
        """
        N = self.G.shape[0]
        in_flight = 4 * self.workers
        pending = deque()
        with one_blas_thread(), ThreadPoolExecutor(self.workers) as ex:
            for s in range(0, N, self.block):
                sl = slice(s, min(N, s + self.block))
                pending.append((sl, ex.submit(fn, sl)))
                if len(pending) >= in_flight:  # a sliding window: no worker waits for a whole group
                    done, fut = pending.popleft()
                    reduce(done, fut.result())
            while pending:
                done, fut = pending.popleft()
                reduce(done, fut.result())
        self.passes += 1
        report(self.progress, self.stage, self.passes, 0)

    def matmat(self, X, extra=None):
        """Return D @ X, (N, r) float64, Fortran-ordered (so it can be orthonormalised in place).

        ``extra(D_block)`` returns per-block statistics (a float, an ndarray or a tuple
        of them); their sum over blocks is left in ``last_stats``.
        """
        X32 = np.asarray(X, dtype=np.float32)
        out = np.empty((self.G.shape[0], X32.shape[1]), dtype=np.float64, order="F")  # QR'd in place
        stats = [None]

        def one(sl):
            Db = self.block_rows(sl)
            return Db @ X32, (extra(Db) if extra is not None else None)

        def reduce(sl, res):
            out[sl] = res[0]
            if res[1] is not None:
                stats[0] = res[1] if stats[0] is None else _add(stats[0], res[1])

        self._map(one, reduce)
        self.last_stats = stats[0]
        return out

    def rmatmat(self, Q):
        """D^T @ Q for a non-square (N, L) distance matrix, block-wise."""
        Q32 = np.asarray(Q, dtype=np.float32)
        acc = np.zeros((self.cols.shape[0], Q32.shape[1]), dtype=np.float64)

        def reduce(sl, res):
            acc.__iadd__(res)

        self._map(lambda sl: self.block_rows(sl).T @ Q32[sl], reduce)
        return acc


def _largest_signs(Q, W, *, block: int = 1 << 16) -> np.ndarray:
    """Per column of U = Q W (Q (N, r), W (r, k)): the sign of its entry of largest magnitude (the first
    such row), 0 read as +1; U is formed ``block`` rows at a time."""
    best = np.full(W.shape[1], -1.0)
    sign = np.ones(W.shape[1])
    for s in range(0, Q.shape[0], block):
        U = Q[s:s + block] @ W
        i = np.argmax(np.abs(U), axis=0)
        v = U[i, np.arange(W.shape[1])]
        better = np.abs(v) > best  # strictly: ties keep the earlier row, as one argmax over all rows does
        best[better] = np.abs(v[better])
        sign[better] = np.sign(v[better])
    sign[sign == 0] = 1
    return sign


def _add(a, b):
    """Sum of two block statistics (floats, ndarrays, or tuples of them)."""
    if isinstance(a, tuple):
        return tuple(_add(x, y) for x, y in zip(a, b))
    return a + b


class Embedding(Estimator):
    """Low-dimensional embedding of the dynamic features.

    Parameters
    ----------
    n_components : int, default=10
        Dimensions kept (the paper: 10; the first 3 are the manifold).
    method : {"pca", "mds"}, default="pca"
    n_landmarks : int or None, default=None
        If set, use distances to this many landmark frames (chosen uniformly at random
        with ``random_state``) instead of all N.
    n_iter : int, default=2
        Power iterations of the randomized range finder.
    oversample : int, default=10
    random_state : int, default=0

    Attributes
    ----------
    embedding_ : ndarray of shape (N, n_components), float32
        F^y.
    explained_variance_ : ndarray of shape (n_components,)
    explained_variance_ratio_ : ndarray of shape (n_components,)
        Fraction of the total variance of the (centred) matrix per component.
    recovered_ratio_ : ndarray of shape (n_components,)
        Cumulative fraction of the variance of the kept components (the paper's
        "first 3 dimensions account for 93% of the recovered variance").
    reference_ : ndarray of shape (L, 2m)
        The column points of D: all training G (L = N) or the landmarks.
    landmarks_ : ndarray of shape (L,) or None
    components_ : ndarray of shape (n_components, L)
        PCA: the principal axes of the rows of D. MDS: the out-of-sample projector.
    center_ : ndarray of shape (L,)
        PCA: the mean row of D. MDS: the column means of D^2.
    n_passes_ : int
        Passes over the blocks of D the fit made.
    n_range_ : int
        Columns of the randomized range finder (``n_components + oversample``, at most L).
    """

    #: builds the products with D; engine.scale.executor swaps in a Dask one for a single fit
    _operator_factory = _DistanceOperator

    _parameter_constraints = {
        "n_components": [Interval(Integral, 1, None, closed="left")],
        "method": [StrOptions(("pca", "mds"))],
        "n_landmarks": [Interval(Integral, 2, None, closed="left"), None],
        "n_iter": [Interval(Integral, 0, None, closed="left")],
        "oversample": [Interval(Integral, 0, None, closed="left")],
        "random_state": ["random_state"],
    }

    #: fitted attributes a manifold file stores and checks on load, as
    #: :func:`engine.files.persist.load_estimator` specs (shape symbols shared across the file: N frames,
    #: m shape components, k embedding dims, L reference points)
    _persisted_attributes = {
        "embedding_": dict(kind="array", dtype="float", shape=("N", "k")),
        "reference_": dict(kind="array", dtype="float", shape=("L", "2m")),
        "components_": dict(kind="array", dtype="float", shape=("k", "L")),
        "center_": dict(kind="array", dtype="float", shape=("L",)),
        "explained_variance_": dict(kind="array", dtype="float", shape=("k",)),
        "explained_variance_ratio_": dict(kind="array", dtype="float", shape=("k",)),
        "recovered_ratio_": dict(kind="array", dtype="float", shape=("k",)),
        "landmarks_": dict(kind="array", dtype="int", shape=("L",), low=0, high="N", none=True),
    }

    def __init__(self, *, n_components=10, method="pca", n_landmarks=None, n_iter=2, oversample=10,
                 random_state=0):
        self.n_components = n_components
        self.method = method
        self.n_landmarks = n_landmarks
        self.n_iter = n_iter
        self.oversample = oversample
        self.random_state = random_state

    def _check(self, G):
        validate_params(self)
        G = np.asarray(G, dtype=np.float32)
        if G.ndim != 2:
            raise ValueError(f"G must be 2-D (N, 2m), got shape {G.shape}; pass one row per frame")
        k, N = int(self.n_components), G.shape[0]
        if k >= N:
            raise ValueError(f"n_components={k} must be at most {N - 1} (N - 1, with N = {N} frames); lower it")
        if self.n_landmarks is not None and not k < int(self.n_landmarks) <= N:
            raise ValueError(f"n_landmarks={self.n_landmarks} must be in {k + 1}..{N} (above n_components={k}, "
                             f"at most N = {N} frames); use None for the full N x N method")
        if not np.isfinite(G).all():
            raise ValueError(f"G holds NaN/inf at frame {int(np.argwhere(~np.isfinite(G))[0, 0])}; "
                             "clean the frames before embedding")
        return G

    def fit(self, G, *, progress: ProgressFn = None):
        """Embed G (N, 2m); F^y lands in ``embedding_`` (N, n_components)."""
        G = self._check(G)
        N = G.shape[0]
        rng = np.random.default_rng(self.random_state)
        if self.n_landmarks is not None and int(self.n_landmarks) < N:
            lm = np.sort(rng.choice(N, size=int(self.n_landmarks), replace=False))
            ref = G[lm]
        else:
            lm, ref = None, G
        L = ref.shape[0]
        block = max(16, min(N, _BLOCK_BYTES // (4 * L)))
        op = self._operator_factory(G, ref, squared=self.method == "mds", block=block, progress=progress,
                                    stage="embedding")
        k = int(self.n_components)
        r = min(k + int(self.oversample), L)
        if self.method == "pca":
            Fy, comps, center, ev, total = self._fit_pca(op, N, L, k, r, rng)
        else:
            Fy, comps, center, ev, total = self._fit_mds(op, N, L, k, r, rng, lm)
        self.embedding_ = np.ascontiguousarray(Fy, dtype=np.float32)
        self.components_ = comps.astype(np.float32)
        self.center_ = center.astype(np.float32)
        self.explained_variance_ = ev
        self.explained_variance_ratio_ = ev / total if total > 0 else np.zeros_like(ev)
        self.recovered_ratio_ = np.cumsum(ev) / ev.sum() if ev.sum() > 0 else np.ones_like(ev)
        self.reference_ = ref
        self.landmarks_ = lm
        self.n_passes_ = op.passes
        self.n_range_ = r
        return self

    # -- PCA of the rows of D (N observations of L features) -------------------
    def _fit_pca(self, op, N, L, k, r, rng):
        # A = D - 1 c^T, c = column means of D (the mean row). D is (N, L).
        def acc(Db):
            return float(np.einsum("ij,ij->", Db, Db, dtype=np.float64)), Db.sum(axis=0, dtype=np.float64)

        # first pass: D @ Omega, and the sum of squares and column sums of D
        # every N x r array is centred in place and orthonormalised in place, and none outlives
        # its use: at ten million frames each is 2 GB and the client holds at most two
        Om = rng.standard_normal((L, r))
        Y = op.matmat(Om, extra=acc)
        sumsq, colsum = op.last_stats
        c = colsum / N
        Y -= (c @ Om)[None, :]
        Q = orthonormal_basis(Y, overwrite=True)
        del Y

        def At(Qm):  # A^T Q = D^T Q - c 1^T Q
            if L == N:  # D symmetric
                out = op.matmat(Qm)
            else:
                out = op.rmatmat(Qm)
            return out - np.outer(c, Qm.sum(axis=0))

        def A(Xm):  # A X = D X - 1 c^T X, a new (N, r) Fortran-ordered array
            out = op.matmat(Xm)
            out -= (c @ Xm)[None, :]
            return out

        for _ in range(int(self.n_iter)):
            Z = orthonormal_basis(At(Q))
            del Q
            Q = orthonormal_basis(A(Z), overwrite=True)
        B = At(Q).T  # (r, L)
        Ub, s, Vt = thin_svd(B)
        s, Vt = s[:k], Vt[:k]
        # deterministic signs: largest |score| of U = Q Ub positive, U read a block of rows at a time
        sign = _largest_signs(Q, Ub[:, :k])
        del Q
        Vt *= sign[:, None]
        # F^y as the rows of A projected on the axes (one more pass): the same numbers as the
        # out-of-sample projection of the training frames, also in the weakest axes, where the
        # range finder's U * s is least converged
        Fy = A(Vt.T)
        total = (sumsq - N * float(c @ c)) / (N - 1)
        ev = s**2 / (N - 1)
        return Fy, Vt, c, ev, total

    # -- classical MDS --------------------------------------------------------------
    def _fit_mds(self, op, N, L, k, r, rng, lm):
        if L != N:
            # landmark MDS (de Silva & Tenenbaum): classical MDS of the landmarks, then
            # triangulate every frame from its squared distances to them.
            sub = _DistanceOperator(op.cols, op.cols, squared=True, block=op.block, progress=None, stage="")
            V, lam, colmean = _mds_eig(sub, L, k, r, rng, int(self.n_iter))
            comps = (V / np.sqrt(lam)[None, :]).T  # (k, L)
            Fy = -0.5 * (op.matmat(comps.T) - colmean @ comps.T)
            total = float(colmean.sum()) / 2.0 / (L - 1)
            return Fy, comps, colmean, lam / (L - 1), total
        V, lam, colmean = _mds_eig(op, N, k, r, rng, int(self.n_iter))
        Fy = V * np.sqrt(lam)[None, :]
        comps = (V / np.sqrt(lam)[None, :]).T
        # total variance of the configuration = trace(B)/(N-1); trace(B) = sum(D^2)/(2N)
        total = float(colmean.sum()) / 2.0 / (N - 1)
        return Fy, comps, colmean, lam / (N - 1), total

    # -- out-of-sample ---------------------------------------------------------------
    def transform(self, G_new) -> np.ndarray:
        """Project new dynamic features (n, 2m) into F^y (n, n_components).

        PCA: the distance row to the fitted reference, centred with the fitted mean row,
        times the axes. MDS: Gower's formula with the squared distances.
        """
        check_is_fitted(self, "embedding_")
        G_new = np.atleast_2d(np.asarray(G_new, dtype=np.float32))
        if G_new.ndim != 2 or G_new.shape[1] != self.reference_.shape[1]:
            raise ValueError(f"G must have shape (n, {self.reference_.shape[1]}), got {G_new.shape}")
        L = self.reference_.shape[0]
        block = max(1, _BLOCK_BYTES // (4 * L))
        ref_sq = np.einsum("ij,ij->i", self.reference_, self.reference_)
        out = np.empty((G_new.shape[0], self.components_.shape[0]), dtype=np.float32)
        for s in range(0, G_new.shape[0], block):
            sl = slice(s, min(G_new.shape[0], s + block))
            if self.method == "pca":
                D = pairwise_distance_block(G_new[sl], self.reference_, ref_sq)
                out[sl] = (D - self.center_) @ self.components_.T
            else:
                D2 = pairwise_distance_block(G_new[sl], self.reference_, ref_sq, squared=True)
                out[sl] = -0.5 * (D2 - self.center_) @ self.components_.T
        return out


def _mds_eig(op, N, k, r, rng, n_iter):
    """Top-k eigenpairs of B = -1/2 J D^2 J by a randomized range finder (D^2 via ``op``)."""
    def B(X, first=False):
        Xc = X - X.mean(axis=0)
        return op.matmat(Xc, extra=(lambda Db: Db.sum(axis=0, dtype=np.float64)) if first else None)

    Om = rng.standard_normal((N, r))
    Y = B(Om, first=True)
    colmean = op.last_stats / N
    Y = -0.5 * (Y - Y.mean(axis=0))
    Q = orthonormal_basis(Y)
    for _ in range(n_iter):
        Y = -0.5 * B(Q)
        Y -= Y.mean(axis=0)
        Q = orthonormal_basis(Y)
    BQ = -0.5 * B(Q)
    BQ -= BQ.mean(axis=0)
    T = Q.T @ BQ
    T = 0.5 * (T + T.T)
    lam, W = np.linalg.eigh(T)
    order = np.argsort(lam)[::-1][:k]
    lam, W = lam[order], W[:, order]
    if np.any(lam <= 0):
        raise ValueError(f"classical MDS found only {int((lam > 0).sum())} positive eigenvalues; "
                         f"lower n_components (now {k})")
    V = Q @ W
    big = np.argmax(np.abs(V), axis=0)
    V *= np.sign(V[big, np.arange(k)])[None, :]
    return V, lam, colmean
