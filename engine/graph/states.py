"""States of the manifold and the directed graph of transitions between them (paper section 3.3).

F^y (its first ``n_dims`` columns) is grouped into K states by K-means. Counts
C_jk of frame transitions j -> k inside utterances (self-transitions included) give

* the adjacency A: ``A_jk = 1`` iff ``C_jk > 0`` and ``j != k`` (bool csr),
* the transition probabilities ``P(k | j) = C_jk / sum_k C_jk`` (row-stochastic csr).

Distances are directed hop counts (one hop ~ one frame) over A — the *future
hemisphere* of a state — and over A^T — its *past hemisphere*: Dijkstra's distances
with unit weights, found by a breadth-first search (:func:`engine.graph.hop_paths.hop_distances`).
Unreachable is ``inf``. There is no transition across an utterance boundary.

SciPy's sparse, graph and spatial packages are imported where they are used: loading a fitted
state graph needs none of them (0.6 s of the explorer's start). A graph read from a file keeps its
saved csr matrices as their arrays until one is first used (:meth:`StateGraph.__getattr__`).
"""
from __future__ import annotations

import warnings
from numbers import Integral
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from engine.constraints import Interval, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.graph.hop_paths import fewest_hop_path, hop_distances
from engine.progress import ProgressFn, report
from engine.recordings.bounds import check_bounds
from engine.recordings.corpus import CorpusWarning
from engine.threads import one_blas_thread

__all__ = ["StateGraph", "UnreachableError", "StateGraphConnectivityWarning", "default_n_states",
           "assign_and_count"]

#: above this many frames K-means runs as MiniBatchKMeans
MINIBATCH_ABOVE = 20000
#: MiniBatchKMeans fits its centroids on a uniform random subset of at most this many frames (every frame
#: is then assigned): scikit-learn draws each mini-batch with a probability vector over all N frames, so a
#: step costs O(N) (a quarter of an hour of steps at 10M frames); early stopping takes a few hundred
#: batches of 4,096, under this many frames in all
KMEANS_FIT_FRAMES = 1_000_000
#: default K is about one state per this many frames ...
FRAMES_PER_STATE = 30
#: ... bounded to this range
MIN_DEFAULT_STATES, MAX_DEFAULT_STATES = 2, 3000


class UnreachableError(ValueError):
    """No directed path joins two states."""


class StateGraphConnectivityWarning(CorpusWarning):
    """The state graph is not strongly connected: some distances are infinite."""


def default_n_states(n_frames: int) -> int:
    """Default K: ``clip(round(N / 30), 2, 3000)``, and never more than N.

    About 30 frames (half a second at 60 Hz) per state: each state is entered and
    left several times, so its transitions are observed rather than guessed; the
    paper's 28,833 frames give 961 states. Above 90,000 frames K stays at 3,000 so
    that the graph queries stay interactive; pass ``n_states`` for more.
    """
    return int(min(n_frames, np.clip(round(n_frames / FRAMES_PER_STATE), MIN_DEFAULT_STATES, MAX_DEFAULT_STATES)))


def assign_and_count(start: int, stop: int, centroids: np.ndarray, Y: np.ndarray, has_next: np.ndarray, *,
                     workers: int = 1) -> tuple[np.ndarray, Any]:
    """States of frames ``start:stop`` and the transitions they start.

    Parameters
    ----------
    start, stop : int
        The block of frames.
    centroids : ndarray of shape (K, d)
    Y : ndarray of shape (N, d)
        All frames (only ``start:stop`` and frame ``stop``, the next one, are read).
    has_next : ndarray of shape (N,), bool
        False at the last frame of each utterance.
    workers : int, default=1
        Threads of the KD-tree query (-1: all cores).

    Returns
    -------
    labels : ndarray of shape (stop - start,), int64
        Nearest centroid of each frame.
    counts : scipy.sparse.coo_matrix of shape (K, K), int64
        Transitions ``i -> i + 1`` for i in the block with ``has_next[i]`` (the last
        one may end in the next block), self-transitions included.
    """
    import scipy.sparse as sp
    from scipy.spatial import cKDTree

    N, K = len(Y), len(centroids)
    end = min(stop + 1, N)
    lab = cKDTree(centroids).query(Y[start:end], workers=workers)[1]
    step = has_next[start:end - 1]
    src, dst = lab[:-1][step], lab[1:][step]
    counts = sp.coo_matrix((np.ones(len(src), np.int64), (src, dst)), shape=(K, K))
    return lab[: stop - start], counts


class StateGraph(Estimator):
    """K-means states of F^y and the directed graph of transitions between them.

    Parameters
    ----------
    n_states : int or None, default=None
        K. None: :func:`default_n_states` (about N/30, between 2 and 3000). Must not
        exceed the number of frames.
    n_dims : int, default=3
        Columns of F^y clustered.
    random_state : int, default=0
        Seed of K-means.
    batch_size : int, default=4096
        Mini-batch size of K-means when N > 20,000.

    Notes
    -----
    K-means is scikit-learn's ``KMeans`` (k-means++ seeding, one initialisation) up to
    20,000 frames and ``MiniBatchKMeans`` (k-means++ seeding on max(3 batches, 2K)
    frames, one initialisation) above, both seeded by ``random_state``: deterministic,
    and at paper scale (28,833 frames) about 0.5 s for K = 1,000 and a few seconds for
    K = 5,000 on two cores (``benchmarks/bench_states.py``).

    Attributes
    ----------
    labels_ : ndarray of shape (N,), int32
        State of each training frame (its nearest centroid: ``predict(Fy) == labels_``).
    centroids_ : ndarray of shape (K, n_dims), float64
        State centres. K can be smaller than ``n_states``: centres that end up with no
        frame (duplicate points, K-means' empty clusters) are dropped and the rest
        renumbered, keeping their order.
    counts_ : scipy.sparse.csr_matrix of shape (K, K), int64
        Transition counts C_jk inside utterances, self-transitions included.
    adjacency_ : scipy.sparse.csr_matrix of shape (K, K), bool
        A_jk = C_jk > 0 for j != k.
    transition_ : scipy.sparse.csr_matrix of shape (K, K), float64
        P(k | j), rows sum to 1. A state with no observed outgoing transition (all its
        frames end an utterance) gets P(j | j) = 1 — it is absorbing — so P stays
        stochastic; A is unaffected.
    scc_labels_ : ndarray of shape (K,), int32
        Strongly connected component of each state.
    n_scc_ : int
        Number of strongly connected components.
    largest_scc_ : int
        Label of the largest one.
    """

    _parameter_constraints = {
        "n_states": [Interval(Integral, 1, None, closed="left"), None],
        "n_dims": [Interval(Integral, 1, None, closed="left")],
        "random_state": ["random_state"],
        "batch_size": [Interval(Integral, 1, None, closed="left")],
    }

    #: fitted attributes a manifold file stores and checks on load, as
    #: :func:`engine.files.persist.load_estimator` specs (shape symbols shared across the file: N frames,
    #: K states, d dims of the centroids)
    _persisted_attributes = {
        "centroids_": dict(kind="array", dtype="float", shape=("K", "d")),
        "labels_": dict(kind="array", dtype="int", shape=("N",), low=0, high="K"),
        "counts_": dict(kind="csr", dtype="int", shape=("K", "K"), low=0),
        "adjacency_": dict(kind="csr", dtype="number", shape=("K", "K")),
        "transition_": dict(kind="csr", dtype="float", shape=("K", "K"), low=0),
        "n_scc_": dict(kind="int", low=1),
        "scc_labels_": dict(kind="array", dtype="int", shape=("K",), low=0),
        "largest_scc_": dict(kind="int", low=0),
    }

    #: :func:`engine.files.persist.load_estimator` leaves the csr attributes as their saved arrays
    #: (``_csr_parts``) until first used: loading a manifold imports no SciPy
    _csr_on_use = True

    def __init__(self, *, n_states: int | None = None, n_dims: int = 3, random_state: int | None = 0,
                 batch_size: int = 4096) -> None:
        self.n_states = n_states
        self.n_dims = n_dims
        self.random_state = random_state
        self.batch_size = batch_size

    def __getattr__(self, name: str) -> Any:
        """A csr attribute read from a file, made from its saved arrays on first use (then kept)."""
        part = (self.__dict__.get("_csr_parts") or {}).get(name)
        if part is None:
            if name in self.__dict__:  # made by another thread since this lookup began
                return self.__dict__[name]
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        import scipy.sparse as sp

        data, indices, indptr, shape = part
        value = sp.csr_matrix((data, indices, indptr), shape=shape)
        setattr(self, name, value)
        self.__dict__["_csr_parts"].pop(name, None)
        return value

    # ------------------------------------------------------------------ input
    def _check_Y(self, Y: ArrayLike, name: str = "Y") -> np.ndarray:
        Y = np.asarray(Y)
        if Y.ndim == 1:
            Y = Y[None, :]
        if Y.ndim != 2 or Y.shape[1] < self.n_dims:
            raise ValueError(f"{name} must be a 2-D (frames, dims) array with at least n_dims={self.n_dims} "
                             f"columns, got shape {Y.shape}")
        Y = Y[:, : self.n_dims]
        bad = ~np.isfinite(Y).all(axis=1)
        if bad.any():
            raise ValueError(f"{name} holds NaN or infinite values (first at frame {int(np.flatnonzero(bad)[0])}); "
                             f"remove or repair those frames")
        return np.ascontiguousarray(Y, dtype=np.float32)

    def _check_state(self, state: int, name: str = "state") -> int:
        check_is_fitted(self, "centroids_")
        K = self.centroids_.shape[0]
        if not isinstance(state, (int, np.integer)) or isinstance(state, bool):
            raise TypeError(f"{name} must be an integer state index, got {state!r}")
        if not 0 <= int(state) < K:
            raise ValueError(f"{name}={state} is out of range: the graph has {K} states (0..{K - 1})")
        return int(state)

    # -------------------------------------------------------------------- fit
    def fit(self, Fy: ArrayLike, bounds: ArrayLike, *, progress: ProgressFn = None, executor: Any = None,
            centroids: ArrayLike | None = None) -> StateGraph:
        """Cluster F^y into states and build the transition graph.

        Parameters
        ----------
        Fy : ndarray of shape (N, k >= n_dims)
        bounds : ndarray of shape (U, 2)
            Utterance ``[start, stop)`` frame ranges; no transition crosses one.
        progress : callable(stage, done, total), optional
        executor : object with ``map_row_blocks``, optional
            Runs the assignment of frames to states and the transition counting one
            block of frames per task (:meth:`engine.scale.executor.DaskExecutor.map_row_blocks`);
            None: in-process. K-means itself is fitted here (mini-batch above
            20,000 frames: it touches a few batches, not every frame). Same result.
        centroids : ndarray of shape (K, n_dims), optional
            State centres fitted before (a manifold file stores the synthesiser's): K-means
            is skipped and every frame is assigned to its nearest centre, so the graph is
            the one the fit that made them gave. K is ``len(centroids)``; ``n_states``
            is not used.

        Returns
        -------
        self

        Warns
        -----
        StateGraphConnectivityWarning
            When the graph is not strongly connected (some states cannot be reached
            from, or cannot reach, the others).
        """
        validate_params(self)
        Y = self._check_Y(Fy, "F^y")
        N = Y.shape[0]
        b = check_bounds(bounds, N)
        if centroids is not None:
            centroids = np.asarray(centroids, dtype=np.float64)
            if centroids.ndim != 2 or centroids.shape[1] != self.n_dims or not 1 <= len(centroids) <= N \
                    or not np.isfinite(centroids).all():
                raise ValueError(f"centroids must be a finite (K, n_dims={self.n_dims}) array with 1 <= K <= N = {N}, "
                                 f"got shape {centroids.shape}; leave it out to fit K-means")
            K = len(centroids)
        else:
            K = default_n_states(N) if self.n_states is None else self.n_states
        if K > N:
            raise ValueError(f"n_states must be an integer in 1..N = 1..{N} (one state per frame at most), "
                             f"got {self.n_states!r}; use fewer states or None for the default")
        stage = "state graph"
        report(progress, stage, 0, 3)

        if centroids is None:
            centroids = self._kmeans(Y, int(K)).astype(np.float64)
        has_next = np.ones(N, bool)
        has_next[b[:, 1] - 1] = False
        if executor is None:
            labels, counts = assign_and_count(0, N, centroids, Y, has_next, workers=-1)
        else:  # one task per block of frames; only labels and sparse K x K counts come back
            parts = executor.map_row_blocks(assign_and_count, N, centroids, Y, has_next)
            labels = np.concatenate([p[0] for p in parts])
            counts = sum((p[1] for p in parts[1:]), parts[0][1])
        import scipy.sparse as sp

        counts = sp.csr_matrix(counts, dtype=np.int64)
        used = np.bincount(labels, minlength=len(centroids)) > 0
        if not used.all():  # an unused state has no frame, so no count: dropping it renumbers the rest
            centroids = centroids[used]
            labels = (np.cumsum(used) - 1)[labels]
            counts = counts[used][:, used]
        labels = labels.astype(np.int32)
        K = len(centroids)
        report(progress, stage, 1, 3)

        counts.sum_duplicates()
        counts.sort_indices()
        moves = counts - sp.diags(counts.diagonal(), format="csr", dtype=np.int64)
        moves.eliminate_zeros()
        adjacency = sp.csr_matrix(moves, dtype=bool)
        adjacency.sort_indices()
        out = np.asarray(counts.sum(axis=1)).ravel()
        dead = out == 0
        P = counts.astype(np.float64) + sp.diags(dead.astype(np.float64), format="csr")
        P = sp.diags(1.0 / np.where(dead, 1.0, out).astype(np.float64)) @ P
        P = sp.csr_matrix(P)
        P.sort_indices()
        report(progress, stage, 2, 3)

        from scipy.sparse.csgraph import connected_components

        n_scc, scc = connected_components(adjacency, directed=True, connection="strong")
        report(progress, stage, 3, 3)  # last chance to cancel: self is still untouched

        self.centroids_, self.labels_ = centroids, labels
        self.counts_, self.adjacency_, self.transition_ = counts, adjacency, P
        self.__dict__.pop("_csr_parts", None)  # a refit of a graph read from a file: its saved arrays go
        self.n_scc_, self.scc_labels_ = int(n_scc), scc.astype(np.int32)
        self.largest_scc_ = int(np.bincount(scc).argmax())
        self._reset_cache()
        if n_scc > 1:
            r = self._reach()
            plural = "s" if r["largest"] != 1 else ""
            warnings.warn(
                f"the state graph is not strongly connected: {n_scc} strongly connected components; "
                f"{r['unreachable_from']} of {K} states are unreachable from the largest component "
                f"({r['largest']} state{plural}) and {r['cannot_reach']} cannot reach it. Distances to and "
                f"from them are infinite; fewer states (lipspace build --states K) or more speech connect the graph.",
                StateGraphConnectivityWarning, stacklevel=2)
        return self

    def _kmeans(self, Y: np.ndarray, K: int) -> np.ndarray:
        # imported here: scikit-learn's clustering package costs a loaded manifold's start-up 0.3-0.8 s
        from sklearn.cluster import KMeans, MiniBatchKMeans
        from sklearn.exceptions import ConvergenceWarning

        N = len(Y)
        with warnings.catch_warnings():
            # duplicate frames can leave fewer distinct clusters than K; empty ones are dropped below
            warnings.simplefilter("ignore", ConvergenceWarning)
            if N > MINIBATCH_ABOVE:
                if N > KMEANS_FIT_FRAMES:  # the same frames for the same random_state
                    pick = np.random.default_rng(self.random_state).choice(N, KMEANS_FIT_FRAMES, replace=False)
                    Y, N = Y[np.sort(pick)], KMEANS_FIT_FRAMES
                bs = int(min(N, self.batch_size))
                km = MiniBatchKMeans(n_clusters=K, batch_size=bs, n_init=1, random_state=self.random_state,
                                     init_size=int(min(N, max(3 * bs, 2 * K))), max_no_improvement=10,
                                     reassignment_ratio=0.01, compute_labels=False)
            else:
                km = KMeans(n_clusters=K, n_init=1, random_state=self.random_state)
            # scikit-learn's float32 distance path upcasts chunk by chunk: slower. The k-means++ seeding's
            # K small products (a few candidates against every frame) on one BLAS thread: the same centres,
            # 1.5-4x sooner on two shared cores (docs/DECISIONS.md, C3)
            with one_blas_thread():
                km.fit(Y.astype(np.float64))
        return km.cluster_centers_

    # ---------------------------------------------------------- graph helpers
    def _reset_cache(self) -> None:
        self._cache: dict[str, Any] = {}

    def _graph(self, transpose: bool) -> Any:
        """A (or A^T) as float64 csr with sorted indices, built once and cached."""
        check_is_fitted(self, "adjacency_")
        cache = self.__dict__.setdefault("_cache", {})
        key = "AT" if transpose else "A"
        if key not in cache:
            import scipy.sparse as sp

            G = sp.csr_matrix(self._graph(False).T) if transpose else sp.csr_matrix(self.adjacency_, dtype=np.float64)
            G.sort_indices()
            cache[key] = G
        return cache[key]

    def _reach(self) -> dict[str, int]:
        K = self.centroids_.shape[0]
        rep = int(np.flatnonzero(self.scc_labels_ == self.largest_scc_)[0])
        fut, past = self.hemispheres(rep)
        return {"largest": int((self.scc_labels_ == self.largest_scc_).sum()),
                "unreachable_from": int(np.isinf(fut).sum()), "cannot_reach": int(np.isinf(past).sum()),
                "K": K}

    # ------------------------------------------------------------------ query
    def prepare_queries(self) -> StateGraph:
        """Build now what the first hemisphere or path query would build: A and A^T as csr.

        Both are cached on the object (not saved). At K = 20,000 states (525k edges) they
        take 5-30 ms, mostly the transpose; a loader calls this in its worker so that the
        first click does not pay for them. Returns self.
        """
        self._graph(False), self._graph(True)
        return self

    def predict(self, Y: ArrayLike) -> np.ndarray:
        """Nearest state of each point.

        Parameters
        ----------
        Y : ndarray of shape (n, k >= n_dims) or (k,)

        Returns
        -------
        ndarray of shape (n,), int32
        """
        check_is_fitted(self, "centroids_")
        Y = self._check_Y(Y)
        cache = self.__dict__.setdefault("_cache", {})
        if "tree" not in cache:
            from scipy.spatial import cKDTree

            cache["tree"] = cKDTree(self.centroids_)
        return cache["tree"].query(Y)[1].astype(np.int32)

    def future(self, state: int) -> np.ndarray:
        """Hop distance from ``state`` to every state over A (its future hemisphere).

        Returns
        -------
        ndarray of shape (K,), float64
            0 at ``state``, ``inf`` where unreachable.
        """
        s = self._check_state(state)
        return hop_distances(self._graph(False), s)

    def past(self, state: int) -> np.ndarray:
        """Hop distance from every state to ``state`` (Dijkstra over A^T: its past hemisphere).

        Returns
        -------
        ndarray of shape (K,), float64
            0 at ``state``, ``inf`` where ``state`` cannot be reached.
        """
        s = self._check_state(state)
        return hop_distances(self._graph(True), s)

    def hemispheres(self, state: int) -> tuple[np.ndarray, np.ndarray]:
        """``(future(state), past(state))``."""
        return self.future(state), self.past(state)

    def min_path(self, a: int, b: int) -> np.ndarray:
        """A minimum-distance (fewest hops) state path from ``a`` to ``b``.

        Its length equals ``future(a)[b]``. Among several paths of fewest hops, the one
        of the predecessor tree of a breadth-first search from ``a`` over A (Dijkstra
        with unit weights): the lexicographically smallest sequence of states. Found by
        a bidirectional search that stops where the balls around ``a`` and ``b`` meet
        (:func:`engine.graph.hop_paths.fewest_hop_path`), not a search of the whole graph.

        Returns
        -------
        ndarray of shape (hops + 1,), int64
            States from ``a`` to ``b`` inclusive; consecutive states are adjacent in A.
            ``[a]`` when ``a == b``.

        Raises
        ------
        UnreachableError
            When no directed path leads from ``a`` to ``b``.
        """
        a, b = self._check_state(a, "a"), self._check_state(b, "b")
        if a == b:
            return np.array([a], dtype=np.int64)
        path = fewest_hop_path(self._graph(False), self._graph(True), a, b)
        if path is None:
            raise UnreachableError(
                f"state {b} is unreachable from state {a}: no sequence of observed transitions leads there "
                f"(state {a} is in strongly connected component {int(self.scc_labels_[a])}, state {b} in "
                f"{int(self.scc_labels_[b])}); see connectivity_report()")
        return path

    def connectivity_report(self) -> str:
        """A few lines: K, edges, mean out-degree, components, reachability."""
        check_is_fitted(self, "adjacency_")
        K = self.centroids_.shape[0]
        E = int(self.adjacency_.nnz)
        out = np.diff(self.adjacency_.indptr)
        dead = int((np.asarray(self.counts_.sum(axis=1)).ravel() == 0).sum())
        r = self._reach()
        return "\n".join([
            f"{K} states, {E} directed edges (self-transitions excluded), "
            f"out-degree mean {E / K:.2f}, min {int(out.min())}, max {int(out.max())}",
            f"{self.n_scc_} strongly connected component{'s' if self.n_scc_ != 1 else ''}; "
            f"the largest holds {r['largest']} state{'s' if r['largest'] != 1 else ''} ({100 * r['largest'] / K:.1f}%)",
            f"{r['unreachable_from']} states unreachable from the largest component, "
            f"{r['cannot_reach']} cannot reach it; {dead} with no outgoing transition",
        ])
