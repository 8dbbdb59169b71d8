"""Dask execution of a build's heavy stages.

:class:`DaskExecutor` runs, on a ``distributed`` cluster,

* per-frame work over a corpus stored in blocks (:meth:`DaskExecutor.map_frame_blocks`:
  the per-speaker sums of the speaker normalisation, the lip aperture): the
  :class:`engine.recordings.frame_blocks.BlockFrames` (paths, row counts, the per-speaker map)
  travels once to each worker, every task reads its own block file;
* the shape space PCA over F: F is stored on disk as one memory-mapped ``.npy`` file
  per block of frames (the corpus's own blocks, or :func:`store_frame_blocks` for a
  corpus in memory); every task reads one block, speaker-normalised, and multiplies it
  in the same task (``F[a:b] X``, ``F[a:b]^T Y[a:b]``), so no block of F is ever held
  as a task's result and a worker's memory is a block or two plus the thin products.
  The randomized range finder's tall products ``F X`` (N x r, float32) stay on the
  workers, one future per block; only ``C x r`` and ``r x r`` products come back,
  summed in block order; F^x (N x m) is gathered at the end. (:func:`open_frame_blocks`
  gives F as a dask array, for use outside the build);
* the embedding's products with the distance matrix D (distances to all frames or to
  the landmarks), one task per block of rows of D, each formed on a worker and
  dropped there; G (N x 2m) is scattered once, the thin (N x r) products come back;
* the out-of-sample projection of new G (:meth:`DaskExecutor.project`) and the
  K-means assignment of frames to states (:meth:`DaskExecutor.assign`), one task per
  block.

* the local tangent frames (:meth:`DaskExecutor.map_row_blocks` over
  :func:`engine.manifold.local_gradients.gradients_block`: the fitted KD-tree, F^y, its steps and
  the opening's changes travel once to each worker, every task returns its block of
  anchors' local gradients);
* the assignment of frames to states and the transition counts
  (:func:`engine.graph.states.assign_and_count`: labels of the block and a sparse K x K count
  matrix per task, summed on the client).

The client keeps the small work: the dynamic features (O(N m), one pass), the
zero-velocity plane and the movement classes (O(N) numpy), the mini-batch K-means fit
(a few thousand frames per step) and the graph of K states. Without an executor
:meth:`engine.manifold.model.Manifold.fit` runs the same algorithms in-process; the two
agree up to round-off (same random draws, same range finder).

The cluster is ``DaskExecutor.connect("local")`` (a ``distributed.LocalCluster`` with
one single-threaded worker per core) or ``DaskExecutor.connect("tcp://host:8786")`` (an
existing scheduler, e.g. started by dask-jobqueue). For a multi-node cluster the block
directory must be on storage every worker can read (``chunk_dir``).
"""
from __future__ import annotations

import os
import shutil
import tempfile
from collections import deque
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from engine.manifold.embedding import pairwise_distance_block
from engine.progress import ProgressFn, report
from engine.recordings.frame_blocks import DEFAULT_BLOCK_FRAMES, BlockFrames, block_slices, store_frame_blocks

__all__ = ["DaskExecutor", "open_frame_blocks"]

#: rows of G per embedding task: a whole number of the in-process blocks of D
_TASK_ROWS = 1 << 16

def _frame_rows(frames, a, b):
    return frames.rows(a, b)


def open_frame_blocks(frames):
    """A dask array (N, C) float32 over block files: ``frames`` is an
    :class:`engine.recordings.frame_blocks.BlockFrames` (read through its speaker normalisation, if
    any) or a list of block file paths. Each block is read by the worker that computes
    it (nothing passes through the client). Each block is a task's result, held until
    every task using it is done; the build's shape space does not use it (its tasks
    read a block and multiply it in one go)."""
    import dask
    import dask.array as da

    if not isinstance(frames, BlockFrames):
        frames = BlockFrames.from_files(list(frames))
    C = frames.shape[1]
    parts = [da.from_delayed(dask.delayed(_frame_rows, pure=True)(frames, a, b), shape=(b - a, C), dtype=np.float32)
             for a, b in frames.block_bounds]
    return da.concatenate(parts, axis=0)


def _first_nonfinite(block, a, b) -> int:
    """First frame (global index) of rows ``[a, b)`` holding NaN or inf, or -1."""
    ok = np.isfinite(block).all(axis=1)
    return -1 if ok.all() else a + int(np.flatnonzero(~ok)[0])


# ------------------------------------------------------------------ block tasks
def _frames_task(fn, frames, a, b):
    return fn(frames.rows(a, b), a, b)


def _dist_times(Gb, cols, cols_sq, X, squared, extra, sub):
    """(D[rows] X, the sum of ``extra`` over its sub-blocks) for a task's rows of G, D formed ``sub`` rows at a time."""
    out = np.empty((Gb.shape[0], X.shape[1]), dtype=np.float32)
    stats = None
    for a in range(0, Gb.shape[0], sub):
        Db = pairwise_distance_block(Gb[a:a + sub], cols, cols_sq, squared=squared)
        np.matmul(Db, X, out=out[a:a + sub])
        if extra is not None:
            st = extra(Db)
            stats = st if stats is None else _add(stats, st)
    return out, stats


def _dist_t_times(Gb, cols, cols_sq, Qb, squared, sub):
    """D[rows]^T Q[rows] for a task's rows of G, float64, D formed ``sub`` rows at a time."""
    acc = np.zeros((cols.shape[0], Qb.shape[1]), dtype=np.float64)
    for a in range(0, Gb.shape[0], sub):
        acc += pairwise_distance_block(Gb[a:a + sub], cols, cols_sq, squared=squared).T @ Qb[a:a + sub]
    return acc


def _block_task(fn, frames, a, b, *args):
    """``fn(F[a:b], *args)``: the block read and used in one task; only ``fn``'s result is kept."""
    return fn(frames.rows(a, b), *args)


def _rows_sum(block):
    return block.sum(axis=0, dtype=np.float64)


def _rows_times(block, X, mx):
    """``(F[a:b] - 1 mu^T) X`` from the block, X (C, r) and ``mu^T X`` (r,): (b - a, r) float32."""
    return block @ X - mx


def _rows_t_times(block, Yb):
    """``F[a:b]^T Y[a:b]`` (C, r; a float32 GEMM) and the column sums of ``Y[a:b]`` (r,), as float64."""
    return (block.T @ Yb).astype(np.float64), Yb.sum(axis=0, dtype=np.float64)


def _rows_project(block, mean, components):
    """F^x of the block: ``(F[a:b] - mean) components^T``."""
    return (block - mean) @ components.T


def _centred_sumsq(block, mean32, rows: int = 1024) -> float:
    """Sum of squares of ``block - mean32`` (float64 sums of float32 differences)."""
    total = 0.0
    for s in range(0, block.shape[0], rows):
        d = block[s:s + rows] - mean32
        total += float(np.einsum("ij,ij->", d, d, dtype=np.float64))
    return total


def _rotated(Yb, Ws):
    """A block of Y in float64 times every r x r matrix of ``Ws`` (P, r, r) in turn."""
    y = Yb.astype(np.float64)
    for W in Ws:
        y = y @ W
    return y


def _rotated_gram(Yb, Ws):
    y = _rotated(Yb, Ws)
    return y.T @ y


def _rotated32(Yb, Ws):
    return _rotated(Yb, Ws).astype(np.float32)


def _svqb_weights(gram):
    """``V diag(w)^-1/2`` of the Gram matrix's eigenpairs; ``w`` below 1e-14 of the largest are
    kept at that floor, not dropped (the width r never changes)."""
    w, V = np.linalg.eigh(0.5 * (gram + gram.T))
    w = np.maximum(w, max(float(w.max()), 1e-300) * 1e-14)
    return V / np.sqrt(w)


def _summed(client, futures, *, window: int = 64):
    """Sum of the results of ``futures`` (arrays, floats or tuples of them) in their order.

    ``futures`` is an iterable that submits its tasks as it is read (:meth:`_DaskFrameProducts._per_block`,
    :func:`_map_thin`): at most two windows of tasks are out at once and a window's results
    are gathered and dropped as the next one runs, so the workers hold a bounded number
    of partial results whatever the number of blocks.
    """
    window = max(int(window), 4 * _total_threads(client))
    total, pending = None, []
    for fut in futures:
        pending.append(fut)
        if len(pending) == 2 * window:
            total = _sum_into(total, client.gather(pending[:window]))
            del pending[:window]
    return _sum_into(total, client.gather(pending))


def _sum_into(total, parts):
    for part in parts:
        total = part if total is None else _add(total, part)
    return total


def _total_threads(client) -> int:
    workers = client.scheduler_info().get("workers", {})
    return sum(int(w.get("nthreads", 0)) for w in workers.values())


def _orthonormal_columns(client, Y, passes: int = 2) -> list:
    """An orthonormal basis of the columns of a tall Y (N, r) held on the workers as one future per block.

    SVQB (Stathopoulos & Wu 2002), ``passes`` times: the r x r Gram matrix is the only thing
    brought back. A pass's rotated Y is not stored: the next pass's Gram task rotates its
    block again (``Y W_1 ... W_p``, float64), and only the last rotation is kept, as float32
    (the range finder's next GEMM takes float32), so that the workers hold at most two thin
    N x r float32 matrices (Y and the basis), never float64 ones. Used instead of dask's
    tall-skinny QR, whose many small LAPACK calls took ~2 s for 4,500 x 110 on two shared
    cores (the Gram pass: one GEMM per block).
    """
    Ws: list[np.ndarray] = []  # the rotations W_1, ..., W_p so far
    for _ in range(passes):
        Ws.append(_svqb_weights(_summed(client, _map_thin(client, _rotated_gram, Y, np.asarray(Ws)))))
    return list(_map_thin(client, _rotated32, Y, np.stack(Ws)))


def _map_thin(client, fn, Y, shared):
    """Futures of ``fn(Y[a:b], shared)``, one task per block's future of Y (submitted as they are
    read), ``shared`` scattered once."""
    shared = client.scatter(shared, broadcast=True, hash=False)
    return (client.submit(fn, yb, shared, pure=False) for yb in Y)


def _add(a, b):
    if isinstance(a, tuple):
        return tuple(_add(x, y) for x, y in zip(a, b))
    return a + b


class _DaskDistanceOperator:
    """The interface of ``engine.manifold.embedding._DistanceOperator`` with one Dask task per block of rows.

    A task takes :data:`_TASK_ROWS` rows of G (a whole number of the in-process blocks) and
    forms its rows of D one in-process block at a time, so at ten million frames a pass is
    ~150 tasks, not ~10,000. Results are written into the output (or summed) in block
    order as they arrive, with at most two windows of tasks out: the client never holds a
    pass's results twice.
    """

    def __init__(self, G, cols, *, squared, block, progress, stage, client):
        self.G, self.cols = G, cols
        self.squared, self.block = squared, block
        self.progress, self.stage = progress, stage
        self.passes = 0
        self.client = client
        self.window = max(8, 4 * _total_threads(client))
        self.slices = block_slices(G.shape[0], max(block, _TASK_ROWS // block * block))
        self._blocks = [client.scatter(np.ascontiguousarray(G[sl]), hash=False) for sl in self.slices]
        self._cols = client.scatter(np.ascontiguousarray(cols, dtype=np.float32), broadcast=True, hash=False)
        self._cols_sq = client.scatter(np.einsum("ij,ij->i", cols, cols), broadcast=True, hash=False)

    def _done(self):
        self.passes += 1
        report(self.progress, self.stage, self.passes, 0)

    def _in_order(self, submit):
        """``(slice, result)`` of ``submit(i)`` for every block i, in block order, ``window`` tasks ahead."""
        pending = deque()
        for i, sl in enumerate(self.slices):
            pending.append((sl, submit(i)))
            if len(pending) > self.window:
                done, fut = pending.popleft()
                yield done, fut.result()
        while pending:
            done, fut = pending.popleft()
            yield done, fut.result()

    def matmat(self, X, extra=None):
        X32 = self.client.scatter(np.asarray(X, dtype=np.float32), broadcast=True, hash=False)
        out = np.empty((self.G.shape[0], np.shape(X)[1]), dtype=np.float64, order="F")  # QR'd in place
        stats = None

        def submit(i):
            return self.client.submit(_dist_times, self._blocks[i], self._cols, self._cols_sq, X32, self.squared,
                                      extra, self.block, pure=False)

        for sl, (prod, st) in self._in_order(submit):  # summed in block order
            out[sl] = prod
            if st is not None:
                stats = st if stats is None else _add(stats, st)
        self.last_stats = stats
        self._done()
        return out

    def rmatmat(self, Q):
        acc = np.zeros((self.cols.shape[0], np.shape(Q)[1]), dtype=np.float64)

        def submit(i):
            Qb = np.ascontiguousarray(Q[self.slices[i]], dtype=np.float32)
            return self.client.submit(_dist_t_times, self._blocks[i], self._cols, self._cols_sq, Qb, self.squared,
                                      self.block, pure=False)

        for _, part in self._in_order(submit):
            acc += part
        self._done()
        return acc


def _project_block(emb, Gb):
    return emb.transform(Gb)


def _assign_block(centroids, Yb):
    return cKDTree(centroids).query(Yb)[1].astype(np.int32)


class _DaskFrameProducts:
    """The range finder's products of the centred frames (:class:`engine.manifold.shape.FrameProducts`'s
    interface) on the Dask workers.

    Every task reads one block of F and multiplies it (``F[a:b] X``, ``F[a:b]^T Y[a:b]``,
    its sums), returning only the thin or small result: no block of F is ever a task's
    result, so a worker holds the block it is reading, not the blocks its later tasks will
    need. The thin N x r matrices are lists of futures, one per block, left on the
    workers; C x r, r x r and C results are summed on the client in block order.
    """

    def __init__(self, executor, frames):
        self.executor = executor
        self.client = executor.client
        self.frames = frames
        self.shape = tuple(frames.shape)
        self._frames = self.client.scatter(frames, broadcast=True, hash=False)

    def _per_block(self, fn, *shared, thin=None):
        """Futures of ``fn(F[a:b], *shared)`` (``thin``: and that block's future of an N x r matrix),
        one task per block, in block order, each submitted as it is read. ``shared`` are
        scattered once."""
        shared = [self.client.scatter(x, broadcast=True, hash=False) for x in shared]
        bounds = self.frames.block_bounds
        own = [()] * len(bounds) if thin is None else [(yb,) for yb in thin]
        return (self.client.submit(_block_task, fn, self._frames, a, b, *shared, *yb, pure=False)
                for (a, b), yb in zip(bounds, own))

    def mean(self) -> np.ndarray:
        mean = _summed(self.client, self._per_block(_rows_sum)) / self.shape[0]
        if not np.isfinite(mean).all():  # NaN/inf somewhere: name the first frame, as in-process
            bad = [i for i in self.executor.map_frame_blocks(_first_nonfinite, self.frames) if i >= 0]
            raise ValueError(f"frame {bad[0] if bad else '?'} holds NaN or inf; clean the corpus before fitting")
        return mean

    def times(self, X, mean32) -> list:  # (F - 1 mu^T) X, left on the workers
        X = X.astype(np.float32)
        return list(self._per_block(_rows_times, X, mean32 @ X))

    def t_times(self, Y, mean32) -> np.ndarray:  # (F - 1 mu^T)^T Y, thin, brought back; float32 GEMMs
        out, ysum = _summed(self.client, self._per_block(_rows_t_times, thin=Y))
        return (out - np.outer(mean32, ysum)).astype(np.float32)

    def orthonormal(self, Y) -> list:
        return _orthonormal_columns(self.client, Y)

    def centred_sumsq(self, mean32) -> float:
        return float(_summed(self.client, self._per_block(_centred_sumsq, mean32)))

    def project(self, mean, components) -> np.ndarray:
        """F^x = (F - mean) components^T (N, m), gathered block by block."""
        parts = self.client.gather(list(self._per_block(_rows_project, mean, components)))
        return np.concatenate(parts)


class DaskExecutor:
    """Runs the shape space and the embedding of a build on a Dask cluster.

    Parameters
    ----------
    client : distributed.Client
    chunk_dir : path or None, default=None
        Where F is stored in blocks; None: a temporary folder removed by :meth:`close`.
        With workers on other machines, give a folder they all read.
    block_frames : int, default=DEFAULT_BLOCK_FRAMES
        Frames per block of F (and per task).
    own_cluster : bool, default=False
        Close the client's cluster in :meth:`close` (set by :meth:`connect` ``("local")``).
    """

    def __init__(self, client, *, chunk_dir=None, block_frames: int = DEFAULT_BLOCK_FRAMES, own_cluster=False):
        if int(block_frames) < 256:
            raise ValueError(f"block_frames must be >= 256 (each block must be taller than the range finder "
                             f"is wide), got {block_frames}")
        self.client = client
        self.block_frames = int(block_frames)
        self._tmp = chunk_dir is None
        self.chunk_dir = Path(tempfile.mkdtemp(prefix="lipspace-blocks-")) if chunk_dir is None else Path(chunk_dir)
        self._own = own_cluster

    @classmethod
    def connect(cls, address: str, **kwargs) -> DaskExecutor:
        """``"local"``: a LocalCluster with one single-threaded worker per core (memory split
        evenly); otherwise the address of a running scheduler (``tcp://host:8786``)."""
        from distributed import Client, LocalCluster

        if address == "local":
            # ":0": the scheduler's HTTP server (it starts one even without a dashboard) on a free port, not
            # 8787, which another cluster on the machine may hold ("Cluster failed to start: Port 8787 is in use")
            cluster = LocalCluster(n_workers=os.cpu_count() or 1, threads_per_worker=1, dashboard_address=":0")
            return cls(Client(cluster), own_cluster=True, **kwargs)
        try:
            client = Client(address, timeout="20s")
        except OSError as exc:
            raise ValueError(f"cannot reach a Dask scheduler at {address!r} ({exc}); start one with "
                             "'dask scheduler' or use --dask local") from None
        return cls(client, **kwargs)

    def describe(self) -> str:
        """``"2 workers, 2 threads at tcp://..."`` for the command line."""
        workers = self.client.scheduler_info().get("workers", {})
        threads = sum(int(w.get("nthreads", 0)) for w in workers.values())
        return f"{len(workers)} workers, {threads} threads at {self.client.scheduler.address}"

    def close(self):
        """Close the client (and the cluster it started) and remove temporary blocks."""
        cluster = self.client.cluster if self._own else None
        self.client.close()
        if cluster is not None:
            cluster.close()
        if self._tmp:
            shutil.rmtree(self.chunk_dir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def map_frame_blocks(self, fn, frames) -> list:
        """``[fn(F[a:b], a, b) for each block file [a, b) of frames]``, one task per block, in order.

        ``frames`` (an :class:`engine.recordings.frame_blocks.BlockFrames`: paths and small matrices)
        travels once to every worker; each task reads its own block file (through the
        speaker normalisation, if any) and returns only ``fn``'s result. Used by the
        speaker normalisation's sums and the lip aperture (:func:`engine.recordings.frame_blocks.map_frames`).
        """
        ff = self.client.scatter(frames, broadcast=True, hash=False)
        futs = [self.client.submit(_frames_task, fn, ff, a, b, pure=False) for a, b in frames.block_bounds]
        return self.client.gather(futs)

    # ------------------------------------------------------------ shape space
    def fit_shape(self, shape, frames, *, progress: ProgressFn = None) -> np.ndarray:
        """Fit ``shape`` (an unfitted :class:`engine.manifold.shape.ShapeSpace`) on F; return F^x (N, m).

        ``ShapeSpace.fit_products``'s range finder (the same random draws, power
        iterations and early stop) over :class:`_DaskFrameProducts`: every task reads one
        block of F and multiplies it, the thin N x r matrices are left on the workers.
        """
        if isinstance(frames, BlockFrames):  # stored in blocks already: the workers read them in place
            shape.validate_frames(frames, finite=False)  # finiteness: checked by the workers below
        else:  # in memory: written out once as blocks for the workers
            frames = BlockFrames.from_files(store_frame_blocks(shape.validate_frames(frames), self.chunk_dir / "frames",
                                                               block_frames=self.block_frames))
        products = _DaskFrameProducts(self, frames)
        shape.fit_products(products, progress=progress)
        Fx = products.project(shape.mean_, shape.components_)
        return np.ascontiguousarray(Fx, dtype=np.float32)

    # -------------------------------------------------------------- embedding
    def fit_embedding(self, emb, G, *, progress: ProgressFn = None):
        """Fit ``emb`` (an unfitted :class:`engine.manifold.embedding.Embedding`) on G with its products with
        D computed by Dask tasks; returns ``emb``."""
        client = self.client

        def factory(*args, **kwargs):
            return _DaskDistanceOperator(*args, client=client, **kwargs)

        emb._operator_factory = factory
        try:
            emb.fit(G, progress=progress)
        finally:
            del emb._operator_factory  # back to the class's in-process operator
        return emb

    # --------------------------------------------------------- out-of-sample
    def _map_rows(self, fn, fixed, X, block):
        fixed_f = self.client.scatter(fixed, broadcast=True, hash=False)
        slices = block_slices(X.shape[0], block) if X.shape[0] else []
        futs = [self.client.submit(fn, fixed_f, np.ascontiguousarray(X[sl]), pure=False) for sl in slices]
        return self.client.gather(futs)

    def project(self, emb, G, *, block: int = 16384) -> np.ndarray:
        """Out-of-sample F^y of dynamic features G (n, 2m) by a fitted embedding, one task per block."""
        G = np.asarray(G, dtype=np.float32)
        parts = self._map_rows(_project_block, emb, G, block)
        return np.concatenate(parts) if parts else emb.transform(G)

    def map_row_blocks(self, fn, n_rows: int, *shared, block: int = 65536) -> list:
        """``[fn(start, stop, *shared) for each block of rows]``, one Dask task per block, in block order.

        The ``shared`` arguments (arrays, fitted objects) are scattered once to every
        worker; each task reads its own rows of them and returns only its block's
        result. Used by the tangent frames (:func:`engine.manifold.local_gradients.gradients_block`)
        and the state graph (:func:`engine.graph.states.assign_and_count`).
        """
        if int(block) < 1:
            raise ValueError(f"block must be a positive number of rows, got {block}")
        # hash=False: a random key per scatter. With content keys, identical data scattered by
        # a client that has just closed (an earlier build on the same scheduler) can be released
        # while this client's tasks wait for it ("lost dependencies")
        futs = [self.client.scatter(a, broadcast=True, hash=False) for a in shared]
        starts = range(0, int(n_rows), int(block))
        tasks = [self.client.submit(fn, a, min(int(n_rows), a + int(block)), *futs, pure=False) for a in starts]
        return self.client.gather(tasks)

    def assign(self, centroids, Y, *, block: int = 65536) -> np.ndarray:
        """K-means assignment: index of the nearest of ``centroids`` (K, d) for each row of Y (n, >= d)."""
        centroids = np.asarray(centroids, dtype=np.float64)
        Y = np.asarray(Y)[:, : centroids.shape[1]]
        parts = self._map_rows(_assign_block, centroids, Y, block)
        return np.concatenate(parts) if parts else np.zeros(0, np.int32)
