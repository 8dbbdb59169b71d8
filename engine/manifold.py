"""The fitted visual speech manifold: the whole pipeline in one object and one file.

``Corpus -> ShapeSpace (X) -> DynamicFeatures (G) -> Embedding (Y) -> TangentFrames,
StateGraph``. The GUI and the command line are two faces over this object.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from engine._atomic import atomic_write
from engine._persist import NpzReadError, dump_estimator, load_estimator, read_npz
from engine.corpus import Corpus, CorpusError
from engine.dynamics import DynamicFeatures, velocities
from engine.embedding import Embedding
from engine.progress import ProgressFn, report
from engine.shape import ShapeSpace

__all__ = ["Manifold", "ManifoldFileError"]

FILE_VERSION = 1
#: corpora whose frames exceed this are saved without F (reconstructed from F^x on load)
MAX_SAVED_FRAME_BYTES = 512 * 2**20


class ManifoldFileError(ValueError):
    """A manifold file cannot be read; the message names the file and the fault."""


class Manifold(BaseEstimator):
    """The visual speech manifold of a corpus.

    Parameters
    ----------
    variance : float, default=0.99
        Variance kept by the shape space X.
    max_components : int, default=100
        Shape components computed.
    n_embedding : int, default=10
        Dimensions of Y kept.
    embedding_method : {"pca", "mds"}, default="pca"
    n_landmarks : int or None, default=None
        Landmark embedding for very large corpora.
    n_states : int or None, default=None
        K of the state graph (None: about N/30, see :class:`engine.states.StateGraph`).
    state_dims : int, default=3
        Dimensions of Y clustered into states.
    n_neighbors : int, default=20
        Neighbourhood size of the local tangent frames.
    random_state : int, default=0

    Attributes
    ----------
    corpus_ : Corpus
    shape_ : ShapeSpace
    dynamics_ : DynamicFeatures
    embedding_ : Embedding
    tangent_ : TangentFrames
    states_ : StateGraph
    Fx_ : ndarray of shape (N, m), float32
        Shape coordinates F^x.
    Fxv_ : ndarray of shape (N, m), float32
        Their velocities F^x'.
    G_ : ndarray of shape (N, 2m), float32
    Fy_ : ndarray of shape (N, n_embedding), float32
        The embedding F^y.
    timings_ : dict of str to float
        Seconds per stage of the last fit.
    """

    def __init__(self, *, variance=0.99, max_components=100, n_embedding=10, embedding_method="pca",
                 n_landmarks=None, n_states=None, state_dims=3, n_neighbors=20, random_state=0):
        self.variance = variance
        self.max_components = max_components
        self.n_embedding = n_embedding
        self.embedding_method = embedding_method
        self.n_landmarks = n_landmarks
        self.n_states = n_states
        self.state_dims = state_dims
        self.n_neighbors = n_neighbors
        self.random_state = random_state

    # ------------------------------------------------------------------ fitting
    def fit(self, corpus: Corpus, *, progress: ProgressFn = None):
        """Fit every stage on ``corpus``. Cancelling (via ``progress``) leaves ``self`` unfitted."""
        from engine.states import StateGraph
        from engine.tangent import TangentFrames

        if not isinstance(corpus, Corpus):
            raise TypeError(f"fit expects an engine.corpus.Corpus, got {type(corpus).__name__}")
        N = corpus.n_frames
        if N < max(12, self.n_embedding + 2):
            raise ValueError(f"{corpus.name}: {N} frames are too few to build a manifold "
                             f"(need at least {max(12, self.n_embedding + 2)})")
        timings = {}
        bounds = corpus.bounds

        t = time.perf_counter()
        shape = ShapeSpace(max_components=self.max_components, variance=self.variance,
                           random_state=self.random_state).fit(corpus.frames, progress=progress)
        Fx = shape.transform(corpus.frames)
        timings["shape"] = time.perf_counter() - t

        t = time.perf_counter()
        dyn = DynamicFeatures().fit(Fx, bounds)
        Fxv = velocities(Fx, bounds)
        G = dyn.transform_pair(Fx, Fxv)
        timings["dynamics"] = time.perf_counter() - t
        report(progress, "dynamic features", 1, 1)

        t = time.perf_counter()
        emb = Embedding(n_components=self.n_embedding, method=self.embedding_method,
                        n_landmarks=self.n_landmarks, random_state=self.random_state).fit(G, progress=progress)
        Fy = emb.embedding_
        timings["embedding"] = time.perf_counter() - t

        t = time.perf_counter()
        report(progress, "tangent frames", 0, 1)
        tangent = TangentFrames(n_neighbors=self.n_neighbors, n_dims=min(3, self.n_embedding)).fit(
            Fy, Fx, Fxv, bounds)
        report(progress, "tangent frames", 1, 1)
        timings["tangent"] = time.perf_counter() - t

        t = time.perf_counter()
        states = StateGraph(n_states=self.n_states, n_dims=min(self.state_dims, self.n_embedding),
                            random_state=self.random_state).fit(Fy, bounds, progress=progress)
        timings["states"] = time.perf_counter() - t

        self.corpus_ = corpus
        self.shape_, self.dynamics_, self.embedding_ = shape, dyn, emb
        self.tangent_, self.states_ = tangent, states
        self.Fx_, self.Fxv_, self.G_, self.Fy_ = Fx, Fxv, G, Fy
        self.timings_ = timings
        self._inverse = None
        return self

    # -------------------------------------------------------------- projections
    def project(self, frames, bounds=None) -> np.ndarray:
        """Out-of-sample F^y for new frames (n, C) forming utterances ``bounds`` (default: one)."""
        check_is_fitted(self, "Fy_")
        frames = np.atleast_2d(np.asarray(frames, dtype=np.float32))
        if bounds is None:
            bounds = np.array([[0, frames.shape[0]]])
        Fx = self.shape_.transform(frames)
        G = self.dynamics_.transform(Fx, bounds)
        return self.embedding_.transform(G)

    @property
    def inverse_map(self):
        """The Delaunay inverse map Y -> X, built on first use."""
        check_is_fitted(self, "Fy_")
        if getattr(self, "_inverse", None) is None:
            from engine.inverse import InverseMap

            self._inverse = InverseMap(n_dims=min(3, self.Fy_.shape[1])).fit(self.Fy_, self.Fx_)
        return self._inverse

    def summary(self) -> dict:
        """Numbers for ``lipspace info`` and the GUI status bar."""
        check_is_fitted(self, "Fy_")
        c = self.corpus_
        return {
            "corpus": c.name, "frames": c.n_frames, "points": c.n_points, "rate_hz": c.rate,
            "utterances": len(c.utterances), "duration_s": round(c.duration, 2),
            "shape_components": int(self.shape_.n_components_),
            "shape_variance_kept": float(self.shape_.recovered_ratio_[self.shape_.n_components_ - 1]),
            "embedding_dims": int(self.Fy_.shape[1]), "embedding_method": self.embedding_method,
            "Y_first3_recovered": float(self.embedding_.recovered_ratio_[min(2, self.Fy_.shape[1] - 1)]),
            "n_states": int(self.states_.centroids_.shape[0]),
        }

    # ------------------------------------------------------------------ file i/o
    _PARTS = {"shape": "shape_", "dynamics": "dynamics_", "embedding": "embedding_",
              "tangent": "tangent_", "states": "states_"}

    def save(self, path, *, include_frames: bool | None = None) -> Path:
        """Write the fitted manifold (and its corpus) to one ``.npz`` file, atomically.

        ``include_frames=None`` stores the corpus frames when they take at most
        512 MiB; otherwise only F^x is stored and :meth:`load` reconstructs the frames
        as ``mean + F^x X^T`` (the shape space's filtered reconstruction).
        """
        check_is_fitted(self, "Fy_")
        path = Path(path)
        if include_frames is None:
            include_frames = self.corpus_.frames.nbytes <= MAX_SAVED_FRAME_BYTES
        d = {"manifold_version": np.array(FILE_VERSION),
             "manifold_params": np.array(json.dumps(self.get_params())),
             "manifold_timings": np.array(json.dumps(self.timings_)),
             "Fx": self.Fx_, "Fxv": self.Fxv_, "G": self.G_, "Fy": self.Fy_}
        d.update(self.corpus_.to_arrays(include_frames=include_frames))
        for name, attr in self._PARTS.items():
            d.update(dump_estimator(getattr(self, attr), name))
        with atomic_write(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, **d)
        return path

    @classmethod
    def load(cls, path) -> "Manifold":
        """Read a manifold written by :meth:`save`, without refitting."""
        from engine.states import StateGraph
        from engine.tangent import TangentFrames

        path = Path(path)
        classes = {"shape": ShapeSpace, "dynamics": DynamicFeatures, "embedding": Embedding,
                   "tangent": TangentFrames, "states": StateGraph}
        try:
            d = read_npz(path)
        except FileNotFoundError:
            raise ManifoldFileError(f"{path}: no such manifold file") from None
        except NpzReadError as exc:
            raise ManifoldFileError(f"{path}: not a readable .npz manifold file ({exc.reason})") from None
        if "manifold_version" not in d:
            hint = " (it is a corpus file: build it with 'lipspace build')" if "corpus_version" in d else ""
            raise ManifoldFileError(f"{path}: not a Lipspace manifold file{hint}")
        version = int(d["manifold_version"])
        if version > FILE_VERSION:
            raise ManifoldFileError(f"{path}: manifold format {version} is newer than this Lipspace "
                                    f"({FILE_VERSION}); upgrade Lipspace")
        self = cls(**json.loads(str(d["manifold_params"])))
        try:
            for name, attr in cls._PARTS.items():
                setattr(self, attr, load_estimator(classes[name], d, name))
            self.Fx_, self.Fxv_, self.G_, self.Fy_ = d["Fx"], d["Fxv"], d["G"], d["Fy"]
            frames = None if "corpus_frames" in d else self.shape_.inverse_transform(self.Fx_)
            self.corpus_ = Corpus.from_arrays(d, frames=frames, source=str(path))
        except (KeyError, ValueError, TypeError) as exc:
            if isinstance(exc, CorpusError):
                raise ManifoldFileError(str(exc)) from None
            raise ManifoldFileError(f"{path}: damaged manifold file ({exc})") from None
        self.timings_ = json.loads(str(d["manifold_timings"]))
        self._inverse = None
        return self
