"""Shape space X: PCA of the frames about the mean frame (paper section 3.1).

The paper fits PCA with EM (Roweis 1997) because F is 28,833 x 12,784. Here a
randomized range finder with implicit centring plays that role: it only ever
multiplies F (block by block) by thin matrices, so neither a dense covariance
(C x C) nor a centred copy of F is formed.

The range finder (:meth:`ShapeSpace.fit_products`) sees F only through its products
with thin matrices: :class:`FrameProducts` computes them in this process, block by
block; :class:`engine.scale.executor.DaskExecutor` computes the same products on Dask
workers and runs the same algorithm.
"""
from __future__ import annotations

from contextlib import nullcontext
from numbers import Integral, Real

import numpy as np

from engine.constraints import Interval, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.progress import ProgressFn, report
from engine.recordings.frame_blocks import BlockFrames
from engine.threads import one_blas_thread

__all__ = ["ShapeSpace", "FrameProducts"]


#: at most this many frames count as a small (interactive) query: one BLAS thread
SMALL_QUERY_ROWS = 4096


def small_query_blas(n_rows: int):
    """One BLAS thread for a small query (a click, a synthesised utterance); every thread above."""
    return one_blas_thread() if n_rows <= SMALL_QUERY_ROWS else nullcontext()


def _row_blocks(n: int, block: int):
    for s in range(0, n, block):
        yield slice(s, min(n, s + block))


def kept_count(s, variance: float) -> int:
    """Components kept: the smallest m whose squared singular values ``s`` (k,) hold ``variance``
    of their sum (at least 1, at most k)."""
    ev = np.asarray(s, dtype=np.float64) ** 2
    cum = np.cumsum(ev) / ev.sum() if ev.sum() > 0 else np.ones_like(ev)
    return max(1, min(int(np.searchsorted(cum, variance - 1e-12) + 1), len(ev)))


def _kept_estimate(Bt, k: int, variance: float):
    """(m, V) of the range finder's current estimate: the kept count and the kept axes (m, C),
    from the small Gram matrix of ``Bt`` (C, r) instead of a full SVD."""
    B = Bt.T.astype(np.float64)
    with one_blas_thread():
        lam, U = np.linalg.eigh(B @ B.T)
    order = np.argsort(lam)[::-1][:k]
    s = np.sqrt(np.clip(lam[order], 0.0, None))
    m = kept_count(s, variance)
    V = (U[:, order[:m]].T @ B) / np.maximum(s[:m], 1e-300)[:, None]
    return m, V


def _moved_degrees(a, b) -> float:
    """Largest angle (degrees) between the kept subspaces of two estimates; inf if m differs."""
    (ma, Va), (mb, Vb) = a, b
    if ma != mb:
        return float("inf")
    cos = np.linalg.svd(Va @ Vb.T, compute_uv=False)
    return float(np.degrees(np.arccos(np.clip(cos.min(), -1.0, 1.0))))


def _range_settled(Bt, k: int, variance: float, tol: float, previous):
    """The range finder's early stop: ``(settled, estimate)`` for this iteration's ``Bt`` (C, r).

    Settled when the kept components moved less than ``tol`` degrees since ``previous``
    (the last call's estimate; None at first). ``tol <= 0``: never settled, no estimate.
    """
    if tol <= 0:
        return False, None
    estimate = _kept_estimate(Bt, k, variance)
    return previous is not None and _moved_degrees(previous, estimate) < tol, estimate


def orthonormal_basis(M, *, overwrite=False):
    """Q of the reduced QR decomposition of ``M`` (n, r), same dtype, on one BLAS thread.

    scipy's LAPACK wrapper releases the GIL while it works; ``numpy.linalg.qr`` holds it
    (seconds at 28,800 rows), which froze the explorer's window while a worker thread
    fitted the shape space.

    ``overwrite=True`` lets LAPACK factorise a Fortran-ordered ``M`` in place (``M`` is
    destroyed, Q may share its memory): the same numbers without the two n x r copies,
    which at ten million rows are gigabytes each.
    """
    from scipy.linalg import qr

    with one_blas_thread():  # small factorisations; the GEMMs over F keep every thread
        return qr(M, mode="economic", check_finite=False, overwrite_a=overwrite)[0]


def thin_svd(B):
    """``numpy.linalg.svd(B, full_matrices=False)`` of a short-wide (or small) matrix, on one BLAS thread."""
    with one_blas_thread():
        return np.linalg.svd(B, full_matrices=False)


class FrameProducts:
    """The products of the centred frames the range finder needs, computed in this process.

    Any object with these attributes and methods can stand in (see
    :meth:`ShapeSpace.fit_products`); thin results may be of any array type its own
    methods accept back (the Dask executor keeps them on its workers).

    Parameters
    ----------
    F : ndarray or BlockFrames of shape (N, C)
    block_size : int
        Rows of F multiplied at once.
    """

    def __init__(self, F, *, block_size=4096):
        self.F = F
        self.shape = tuple(F.shape)
        self.block = max(1, int(block_size))

    def mean(self) -> np.ndarray:
        """The mean frame (C,), float64."""
        N, C = self.shape
        mean = np.zeros(C, dtype=np.float64)
        for sl in _row_blocks(N, self.block):
            mean += self.F[sl].sum(axis=0, dtype=np.float64)
        return mean / N

    def times(self, X, mean32):
        """(F - 1 mu^T) X for X (C, r): (N, r) float32."""
        X = X.astype(np.float32)
        out = np.empty((self.shape[0], X.shape[1]), dtype=np.float32)
        mx = mean32 @ X
        for sl in _row_blocks(self.shape[0], self.block):
            out[sl] = self.F[sl] @ X - mx
        return out

    def t_times(self, Y, mean32) -> np.ndarray:
        """(F - 1 mu^T)^T Y for Y (N, r) from :meth:`times` or :meth:`orthonormal`: (C, r) float32."""
        Y = Y.astype(np.float32)
        out = np.zeros((self.shape[1], Y.shape[1]), dtype=np.float32)
        for sl in _row_blocks(self.shape[0], self.block):
            out += self.F[sl].T @ Y[sl]
        out -= np.outer(mean32, Y.sum(axis=0))
        return out

    def orthonormal(self, Y):
        """An orthonormal basis of the columns of Y (N, r) from :meth:`times`."""
        return orthonormal_basis(Y)

    def centred_sumsq(self, mean32) -> float:
        """Sum of squares of F - 1 mu^T (float64 sums of float32 differences)."""
        total = 0.0
        for sl in _row_blocks(self.shape[0], self.block):  # no float64 copy of the block
            d = self.F[sl] - mean32
            total += float(np.einsum("ij,ij->", d, d, dtype=np.float64))
        return total


class ShapeSpace(Estimator):
    """PCA shape space of lip frames.

    Parameters
    ----------
    max_components : int, default=100
        Components computed (the paper: 100). Clipped to ``min(N, C) - 1``.
    variance : float in (0, 1], default=0.99
        Keep the smallest ``m`` whose components hold this fraction of the variance
        of the components computed (the paper: 30 components hold 99%).
    n_iter : int, default=3
        Most power iterations of the randomized range finder.
    tol : float or None, default=0.05
        Stop iterating early once an iteration changes neither the number of kept
        components nor their subspace by ``tol`` degrees or more (each iteration costs
        two passes over F; the check costs an r x r eigenproblem). The range finder has
        ``max_components + 10`` columns while a few tens are kept, so it converges
        in one or two iterations; None or 0 always runs ``n_iter``.
    block_size : int, default=4096
        Rows of F multiplied at once (memory is ``block_size * C`` floats).
    random_state : int, default=0

    Attributes
    ----------
    mean_ : ndarray of shape (C,)
    components_ : ndarray of shape (m, C)
        Orthonormal rows. Component 1 is oriented so that its positive direction
        spreads the points apart (opening); the others have their largest loading positive.
    explained_variance_ : ndarray of shape (m,)
    explained_variance_ratio_ : ndarray of shape (m,)
        Fraction of the *total* variance of F per kept component.
    scree_ : ndarray of shape (n_computed,)
        Fraction of the total variance per computed component (the scree).
    recovered_ratio_ : ndarray of shape (n_computed,)
        Cumulative fraction of the variance of the computed components.
    total_variance_ : float
    n_components_ : int
    n_iter_ : int
        Power iterations done (at most ``n_iter``).
    n_range_ : int
        Columns of the randomized range finder (computed components + oversampling):
        every product with F is an (N, C) x (C, ``n_range_``) GEMM.
    """

    _parameter_constraints = {
        "max_components": [Interval(Integral, 1, None, closed="left")],
        "variance": [Interval(Real, 0, 1, closed="right")],
        "n_iter": [Interval(Integral, 0, None, closed="left")],
        "tol": [Interval(Real, 0, None, closed="left"), None],
        "block_size": [Interval(Integral, 1, None, closed="left")],
        "random_state": ["random_state"],
    }

    #: fitted attributes a manifold file stores and checks on load, as
    #: :func:`engine.files.persist.load_estimator` specs (shape symbols shared across the file: N frames,
    #: C coordinates per frame, m kept components, M computed components)
    _persisted_attributes = {
        "mean_": dict(kind="array", dtype="float", shape=("C",)),
        "components_": dict(kind="array", dtype="float", shape=("m", "C")),
        "explained_variance_": dict(kind="array", dtype="float", shape=("m",)),
        "explained_variance_ratio_": dict(kind="array", dtype="float", shape=("m",)),
        "scree_": dict(kind="array", dtype="float", shape=("M",)),
        "recovered_ratio_": dict(kind="array", dtype="float", shape=("M",)),
        "n_components_": dict(kind="int", low=1),
    }

    def __init__(self, *, max_components=100, variance=0.99, n_iter=3, tol=0.05, block_size=4096,
                 random_state=0):
        self.max_components = max_components
        self.variance = variance
        self.n_iter = n_iter
        self.tol = tol
        self.block_size = block_size
        self.random_state = random_state

    def validate_frames(self, F, *, finite=True):
        """The parameters, and F (N, C) as :meth:`fit` checks them: 2-D, enough frames, (``finite``) no NaN/inf.

        F stored in blocks (``engine.recordings.frame_blocks.BlockFrames``) is read a
        window at a time, never gathered. Returns F (an ndarray unless stored in blocks).
        """
        validate_params(self)
        F = F if isinstance(F, BlockFrames) else np.asarray(F)
        if F.ndim != 2:
            raise ValueError(f"frames must be 2-D (n_frames, n_coordinates), got shape {F.shape}; "
                             "pass one row per frame")
        if F.shape[0] < 3:
            raise ValueError(f"need at least 3 frames to fit a shape space, got {F.shape[0]}; pass a longer corpus")
        for sl in _row_blocks(F.shape[0], int(self.block_size)) if finite else ():  # no N x C bool copy
            ok = np.isfinite(F[sl]).all(axis=1)
            if not ok.all():
                bad = sl.start + int(np.flatnonzero(~ok)[0])
                raise ValueError(f"frame {bad} holds NaN or inf; clean the corpus before fitting")
        return F

    def fit(self, F, *, progress: ProgressFn = None):
        """Fit the shape space.

        Parameters
        ----------
        F : ndarray of shape (N, C)
        progress : callable, optional
            ``progress(stage, done, total)``; raise :class:`engine.progress.Cancelled` to stop.
        """
        F = self.validate_frames(F)
        return self.fit_products(FrameProducts(F, block_size=self.block_size), progress=progress)

    def fit_products(self, products, *, progress: ProgressFn = None):
        """Fit the shape space from the products of the frames with thin matrices.

        The randomized range finder with implicit centring: ``k + 10`` random directions,
        at most ``n_iter`` power iterations (stopped early by ``tol``), the SVD of the
        small projected matrix.

        Parameters
        ----------
        products : FrameProducts or alike
            ``shape`` (N, C) of the frames (checked by :meth:`validate_frames`), ``mean()``,
            ``times(X, mean32)``, ``t_times(Y, mean32)``, ``orthonormal(Y)`` and
            ``centred_sumsq(mean32)``, as :class:`FrameProducts`.
        progress : callable, optional
        """
        validate_params(self)
        N, C = products.shape
        rng = np.random.default_rng(self.random_state)
        k = int(min(self.max_components, N - 1, C))
        p = min(10, min(N, C) - k)
        mean = products.mean()
        mean32 = mean.astype(np.float32)
        total_steps = 2 * self.n_iter + 3
        step = 0

        Q = products.times(rng.standard_normal((C, k + p)).astype(np.float32), mean32)
        step += 1
        report(progress, "shape space", step, total_steps)
        Q = products.orthonormal(Q)
        tol = float(self.tol or 0.0)
        previous, it = None, 0
        while True:
            Bt = products.t_times(Q, mean32)  # (C, k+p): B^T for this Q, and the next iteration's input
            step += 1
            report(progress, "shape space", step, total_steps)
            if it >= self.n_iter:
                break
            settled, previous = _range_settled(Bt, k, float(self.variance), tol, previous)
            if settled:  # an iteration no longer moves the kept components
                break
            # the C x r basis: small, in-process, one BLAS thread; the N x r one by the products.
            # The old N x r Q goes first: with it, three N x r matrices would be held at once
            del Q
            Q = products.orthonormal(products.times(orthonormal_basis(Bt), mean32))
            it += 1
            step += 1
            report(progress, "shape space", step, total_steps)
        B = Bt.T  # (k+p, C)
        self.n_iter_ = it
        _, s, Vt = thin_svd(B.astype(np.float64))
        s, Vt = s[:k], Vt[:k]
        total = products.centred_sumsq(mean32)
        report(progress, "shape space", total_steps, total_steps)
        self.n_range_ = k + p
        return self._set_fitted(s, Vt, total, N, mean)

    def _set_fitted(self, s, Vt, total, N, mean):
        """Fitted attributes from the top singular values ``s`` (k,) and axes ``Vt`` (k, C) of
        the centred F, its total sum of squares ``total``, N and the mean frame (C,)."""
        ev = s**2 / (N - 1)
        total_var = total / (N - 1)
        scree = ev / total_var if total_var > 0 else np.zeros_like(ev)
        cum = np.cumsum(ev) / ev.sum() if ev.sum() > 0 else np.ones_like(ev)
        m = kept_count(s, float(self.variance))
        Vt = self._orient(Vt, mean)
        self.mean_ = np.asarray(mean, dtype=np.float32)
        self.components_ = Vt[:m].astype(np.float32)
        self.explained_variance_ = ev[:m]
        self.explained_variance_ratio_ = scree[:m]
        self.scree_ = scree
        self.recovered_ratio_ = cum
        self.total_variance_ = total_var
        self.n_components_ = m
        return self

    @staticmethod
    def _orient(Vt, mean):
        Vt = Vt.copy()
        big = np.argmax(np.abs(Vt), axis=1)
        Vt *= np.sign(Vt[np.arange(len(Vt)), big])[:, None]
        # component 1: positive = points spread apart (opening). Derivative of the summed
        # squared distance of points from their centroid along the component.
        for dims in (3, 2):
            if mean.size % dims == 0:
                break
        P = mean.reshape(-1, dims)
        c = Vt[0].reshape(-1, dims)
        grow = float(((P - P.mean(0)) * (c - c.mean(0))).sum())
        if grow < 0:
            Vt[0] = -Vt[0]
        return Vt

    def transform(self, F):
        """Project frames: ndarray (n, C) -> F^x, ndarray (n, m) float32."""
        check_is_fitted(self, "components_")
        F = F if isinstance(F, BlockFrames) else np.asarray(F, dtype=np.float32)
        if F.ndim != 2 or F.shape[1] != self.mean_.shape[0]:
            raise ValueError(f"frames must have shape (n, {self.mean_.shape[0]}), got {F.shape}")
        out = np.empty((F.shape[0], self.n_components_), dtype=np.float32)
        for sl in _row_blocks(F.shape[0], max(1, int(self.block_size))):
            out[sl] = (F[sl] - self.mean_) @ self.components_.T
        return out

    def inverse_transform(self, Fx):
        """Reconstruct frames: F^x (n, m') with m' <= m -> F (n, C) = mean + F^x X^T.

        Up to ``SMALL_QUERY_ROWS`` frames (a click, an utterance) on one BLAS thread.
        """
        check_is_fitted(self, "components_")
        Fx = np.atleast_2d(np.asarray(Fx, dtype=np.float32))
        m = Fx.shape[1]
        if m > self.n_components_:
            raise ValueError(f"F^x has {m} columns but the shape space has {self.n_components_} components")
        with small_query_blas(Fx.shape[0]):
            return self.mean_ + Fx @ self.components_[:m]

    def component_deformation(self, index: int, amount_sd: float = 2.0):
        """Frame of the mean shape moved ``amount_sd`` standard deviations along one component.

        Returns ndarray of shape (C,).
        """
        check_is_fitted(self, "components_")
        if not 0 <= index < self.n_components_:
            raise ValueError(f"component {index} out of range 0..{self.n_components_ - 1}")
        sd = float(np.sqrt(self.explained_variance_[index]))
        return self.mean_ + amount_sd * sd * self.components_[index]
