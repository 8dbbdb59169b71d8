"""The fitted visual speech manifold: the whole pipeline in one object and one file.

``Corpus -> ShapeSpace (X) -> DynamicFeatures (G) -> Embedding (Y) -> TangentFrames,
StateGraph``. The GUI and the command line are two faces over this object.
"""
from __future__ import annotations

import functools
import json
import os
import re
import time
from collections.abc import Mapping
from numbers import Integral
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from engine.constraints import Interval, StrOptions, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.files.atomic import atomic_write
from engine.files.persist import NpzReadError, dump_estimator, read_npz, source_fingerprint
from engine.manifold.dynamics import SCALES, DynamicFeatures
from engine.manifold.embedding import Embedding
from engine.manifold.manifold_file import FILE_VERSION, read_fitted
from engine.manifold.shape import ShapeSpace, small_query_blas
from engine.progress import ProgressFn, report
from engine.recordings.bounds import velocities
from engine.recordings.corpus import Corpus, CorpusError
from engine.recordings.registration import SPEAKER_MODES

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from engine.manifold.buildplan import BuildPlan
    from engine.manifold.inverse import InverseMap

__all__ = ["project_x", "Manifold", "ManifoldFileError", "algorithm_fingerprint", "fit_modules"]

#: corpora whose frames exceed this are saved without F (reconstructed from F^x on load)
MAX_SAVED_FRAME_BYTES = 512 * 2**20


#: an import statement of an engine module: ``import engine.x[ as y][, ...]`` or ``from engine.x import a, b``
#: (its names in parentheses over several lines too)
_IMPORT = re.compile(r"^[ \t]*(?:from[ \t]+(engine(?:\.\w+)*)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)"
                     r"|import[ \t]+(engine[^\n]*))", re.M)


def _engine_imports(text: str) -> list[str]:
    """The engine names the source ``text`` imports (modules, and ``module.name`` for each name taken from one)."""
    out = []
    for m in _IMPORT.finditer(text):
        if m.group(1):
            names = re.sub(r"#[^\n]*", "", m.group(2)).strip().strip("()")
            out += [m.group(1)] + [f"{m.group(1)}.{n.split()[0]}" for n in names.split(",") if n.strip()]
        else:
            out += [p.split()[0] for p in re.sub(r"#.*", "", m.group(3)).split(",") if p.strip()]
    return [n for n in out if n.split(".")[0] == "engine"]


@functools.lru_cache(maxsize=1)
def fit_modules() -> tuple[str, ...]:
    """The engine modules whose code determines a fitted manifold: this module and every engine
    module it imports, directly or through others, at module level or inside functions, with the
    packages holding them (read from their sources, so a module a new import brings in is covered
    without being listed). The import statements are found by a pattern, not by parsing each
    module (every start of the explorer computes this key: 20 ms instead of 0.2-0.5 s)."""
    seen, todo = {}, [__name__]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen[name] = path = _module_file(name)
        if path is None:
            continue
        parts = name.split(".")
        todo += [".".join(parts[:k]) for k in range(2, len(parts))]  # its packages' __init__ run first
        with open(path, encoding="utf-8") as fh:
            todo += _engine_imports(fh.read())
    return tuple(sorted(n for n, p in seen.items() if p is not None))


def _module_file(name: str) -> str | None:
    """The source file of engine module ``name``, or None when ``name`` is no module (an imported
    function); found on disk beside this package, without importing anything."""
    root = Path(__file__).resolve().parents[1]  # the engine package
    parts = name.split(".")[1:]
    for cand in (root.joinpath(*parts).with_suffix(".py") if parts else None, root.joinpath(*parts, "__init__.py")):
        if cand is not None and cand.is_file():
            return str(cand)
    return None


def algorithm_fingerprint(params: dict | None = None) -> str:
    """Key for caches of fitted manifolds: a hash of the fitting code and the fit parameters.

    ``params`` defaults to :class:`Manifold`'s defaults. A manifold cached under another
    fingerprint was made by other code or settings and must be rebuilt.
    """
    params = Manifold().get_params() if params is None else params
    return source_fingerprint(fit_modules(), {"file_version": FILE_VERSION, "params": params})


class ManifoldFileError(ValueError):
    """A manifold file cannot be read; the message names the file and the fault."""


class Manifold(Estimator):
    """The visual speech manifold of a corpus.

    Parameters
    ----------
    variance : float, default=0.99
        Variance kept by the shape space X.
    max_components : int, default=100
        Shape components computed.
    n_embedding : int, default=16
        Dimensions of Y kept (the tangent frames are read in all of them, or the first
        10, whichever predicts the lips' held-out movement better).
    embedding_method : {"pca", "mds"}, default="pca"
    n_landmarks : int or None, default=None
        Landmark embedding with this many landmarks. None: chosen by size
        (:func:`engine.manifold.buildplan.plan_build`: exact up to ``landmarks_above`` frames,
        2,000 landmarks above).
    landmarks_above : int, default=50000
        Frames above which the embedding uses landmarks when ``n_landmarks`` is None.
    n_states : int or None, default=None
        K of the state graph (None: about N/30, see :class:`engine.graph.states.StateGraph`).
    state_dims : int, default=3
        Dimensions of Y clustered into states.
    n_neighbors : int or None, default=None
        Neighbourhood size of the local tangent frames. None: chosen for the corpus by
        held-out validation (:class:`engine.manifold.tangent.TangentFrames`).
    random_state : int, default=0
    speaker_normalisation : {"auto", "mean", "mean+scale", "none"}, default="auto"
        Per-speaker normalisation of the frames before the shape space
        (:func:`engine.recordings.registration.normalise_speakers`; "auto": "mean" when the
        utterances name two or more speakers). ``corpus_`` holds the normalised frames.
    dynamics_scale : str, default="max"
        How each block of the dynamic features G is scaled
        (:class:`engine.manifold.dynamics.DynamicFeatures`): "max" (the paper's largest entry) or
        "pQ", the Q-th percentile of absolute values (robust to outlying frames).

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
    state_x_ : ndarray of shape (K, m) or None
        The Delaunay inverse map at every state centroid, stored in the file so that
        synthesis needs no tetrahedralisation in a new process (None when the states
        live in other dims than the map's 3, when the build took the landmark path, or
        the file predates it).
    timings_ : dict of str to float
        Seconds per stage of the last fit.
    synthesis_choice_ : dict or None
        The synthesis methods' settings and the method measured best per protocol on the
        corpus's own validation split (:func:`engine.synthesis.method_choice.fit_choice`, which
        ``lipspace build`` runs after :meth:`fit`), stored in the file; None until measured
        (:meth:`fit` resets it). JSON-able.
    synthesis_states_ : ndarray of shape (K, d) or None
        The synthesiser's state centres at those settings, fitted on every frame, so that the
        first synthesis assigns frames to them instead of running K-means.
    synthesis_models_ : dict of str to ndarray
        The phone models measured best, fitted on every utterance, as the arrays
        :func:`engine.files.persist.dump_estimator` makes (read back by
        :func:`engine.synthesis.stored_choice.stored_model`); empty when none.
    """

    _parameter_constraints = {
        "variance": ShapeSpace._parameter_constraints["variance"],
        "max_components": ShapeSpace._parameter_constraints["max_components"],
        "n_embedding": Embedding._parameter_constraints["n_components"],
        "embedding_method": Embedding._parameter_constraints["method"],
        "n_landmarks": Embedding._parameter_constraints["n_landmarks"],
        "n_states": [Interval(Integral, 1, None, closed="left"), None],
        "state_dims": [Interval(Integral, 1, None, closed="left")],
        "n_neighbors": [Interval(Integral, 3, None, closed="left"), None],
        "random_state": ["random_state"],
        "speaker_normalisation": [StrOptions(SPEAKER_MODES)],
        "landmarks_above": [Interval(Integral, 1, None, closed="left")],
        "dynamics_scale": SCALES,
    }

    def __init__(self, *, variance: float = 0.99, max_components: int = 100, n_embedding: int = 16,
                 embedding_method: str = "pca", n_landmarks: int | None = None, n_states: int | None = None,
                 state_dims: int = 3, n_neighbors: int | None = None, random_state: int | None = 0,
                 speaker_normalisation: str = "auto", landmarks_above: int = 50000,
                 dynamics_scale: str = "max") -> None:
        self.variance = variance
        self.max_components = max_components
        self.n_embedding = n_embedding
        self.embedding_method = embedding_method
        self.n_landmarks = n_landmarks
        self.n_states = n_states
        self.state_dims = state_dims
        self.n_neighbors = n_neighbors
        self.random_state = random_state
        self.speaker_normalisation = speaker_normalisation
        self.landmarks_above = landmarks_above
        self.dynamics_scale = dynamics_scale

    # ------------------------------------------------------------------ fitting
    def fit(self, corpus: Corpus, *, progress: ProgressFn = None, executor: Any = None,
            plan: BuildPlan | None = None) -> Manifold:
        """Fit every stage on ``corpus``. Cancelling (via ``progress``) leaves ``self`` unfitted.

        ``plan``: the :class:`~engine.manifold.buildplan.BuildPlan` of this corpus and these
        parameters when the caller already made it (to show it before the fit); None makes it here.

        ``executor``: None fits in-process; an :class:`engine.scale.executor.DaskExecutor` runs the
        shape space, the embedding, the local tangent frames and the assignment to states
        with the transition counts as Dask work (same results up to round-off).
        """
        from engine.graph.states import StateGraph
        from engine.manifold.buildplan import plan_build
        from engine.manifold.tangent import TangentFrames

        validate_params(self)
        if not isinstance(corpus, Corpus):
            raise TypeError(f"fit expects an engine.recordings.corpus.Corpus, got {type(corpus).__name__}")
        from engine.recordings.kinematics import lip_aperture
        from engine.recordings.registration import normalise_speakers, warn_if_split

        corpus = normalise_speakers(corpus, mode=self.speaker_normalisation, executor=executor)
        N = corpus.n_frames
        if N < max(12, self.n_embedding + 2):
            raise ValueError(f"{corpus.name}: {N} frames are too few to build a manifold "
                             f"(need at least {max(12, self.n_embedding + 2)}); add utterances or lower n_embedding")
        timings = {}
        bounds = corpus.bounds

        if plan is None:
            plan = plan_build(N, n_landmarks=self.n_landmarks, landmarks_above=self.landmarks_above)
        elif plan.n_frames != N:
            raise ValueError(f"plan is for {plan.n_frames} frames but {corpus.name} has {N}; "
                             "make it with plan_build(corpus.n_frames, ...) or leave it out")
        t = time.perf_counter()
        shape = ShapeSpace(max_components=self.max_components, variance=self.variance,
                           random_state=self.random_state)
        if executor is None:
            Fx = shape.fit(corpus.frames, progress=progress).transform(corpus.frames)
        else:
            Fx = executor.fit_shape(shape, corpus.frames, progress=progress)
        timings["shape"] = time.perf_counter() - t

        t = time.perf_counter()
        dyn = DynamicFeatures(scale=self.dynamics_scale).fit(Fx, bounds)
        Fxv = velocities(Fx, bounds)
        G = dyn.transform_pair(Fx, Fxv)
        timings["dynamics"] = time.perf_counter() - t
        report(progress, "dynamic features", 1, 1)

        t = time.perf_counter()
        emb = Embedding(n_components=self.n_embedding, method=self.embedding_method,
                        n_landmarks=plan.n_landmarks, random_state=self.random_state)
        emb = emb.fit(G, progress=progress) if executor is None else executor.fit_embedding(emb, G, progress=progress)
        Fy = emb.embedding_
        timings["embedding"] = time.perf_counter() - t

        t = time.perf_counter()
        report(progress, "tangent frames", 0, 1)
        opening, source, unit = lip_aperture(corpus, executor=executor), "lip aperture", corpus.unit_label  # lips part
        if opening is None:
            opening, source, unit = np.asarray(Fx[:, 0], dtype=np.float64), "first shape component F^x_1", ""
        tangent = TangentFrames(n_neighbors=self.n_neighbors, random_state=self.random_state).fit(
            Fy, bounds, opening, rate=corpus.rate, source=source, unit=unit, executor=executor)
        report(progress, "tangent frames", 1, 1)
        timings["tangent"] = time.perf_counter() - t

        t = time.perf_counter()
        states = StateGraph(n_states=self.n_states, n_dims=min(self.state_dims, self.n_embedding),
                            random_state=self.random_state).fit(Fy, bounds, progress=progress, executor=executor)
        timings["states"] = time.perf_counter() - t
        warn_if_split(states, corpus)  # names speakers / recordings when the graph splits along them

        self.corpus_ = corpus
        self.shape_, self.dynamics_, self.embedding_ = shape, dyn, emb
        self.tangent_, self.states_ = tangent, states
        self.Fx_, self.Fxv_, self.G_, self.Fy_ = Fx, Fxv, G, Fy
        self._inverse: InverseMap | None = None
        self.synthesis_choice_ = self.synthesis_states_ = None  # measured on this fit by fit_choice
        self.synthesis_models_: dict[str, Any] = {}
        t = time.perf_counter()
        report(progress, "inverse map", 0, 1)
        # exact-sized builds tetrahedralise every frame (the inverse map synthesis uses anyway); above
        # (a million frames) that costs minutes and gigabytes, so the map at the state points is read
        # from local triangulations (engine.manifold.inverse.delaunay_at: the same tetrahedra)
        self.state_x_ = self._state_x(local=plan.n_landmarks is not None)
        report(progress, "inverse map", 1, 1)
        timings["inverse map"] = time.perf_counter() - t
        self.timings_ = timings
        return self

    def _state_x(self, *, local: bool = False) -> np.ndarray | None:
        """(K, m) the Delaunay inverse map at every state centroid (first 3 dims), or None.

        ``local``: from local triangulations around each centroid (:func:`engine.manifold.inverse.delaunay_at`)
        instead of the tetrahedralisation of every frame; a centroid it cannot place (outside
        the hull, a degenerate neighbourhood) is mapped by the whole map.
        """
        C = np.asarray(self.states_.centroids_, dtype=np.float64)
        if C.shape[1] != min(3, self.Fy_.shape[1]):
            return None  # states in other dims than the map: synthesis maps its points itself
        if not local or C.shape[1] != 3:
            return np.asarray(self.inverse_map.transform(C))
        from engine.manifold.inverse import delaunay_at

        X = delaunay_at(self.Fy_, self.Fx_, C)
        lost = np.isnan(X).any(axis=1)
        if lost.any():
            X[lost] = self.inverse_map.transform(C[lost])
        return X.astype(np.asarray(self.Fx_).dtype)

    def state_inverse(self) -> np.ndarray | None:
        """(K, m) the Delaunay inverse map at every state centroid (``state_x_``), or None when the
        states live in other dims than the map's. A file without it (a large build of an older
        Lipspace) gets it here, once, from local triangulations."""
        check_is_fitted(self, "Fy_")
        if getattr(self, "state_x_", None) is None:
            self.state_x_ = self._state_x(local=True)
        return self.state_x_

    # -------------------------------------------------------------- projections
    def project(self, frames: ArrayLike, bounds: ArrayLike | None = None) -> np.ndarray:
        """Out-of-sample F^y for new frames (n, C) forming utterances ``bounds`` (default: one).

        Up to ``engine.manifold.shape.SMALL_QUERY_ROWS`` frames on one BLAS thread (interactive).
        """
        check_is_fitted(self, "Fy_")
        frames = np.atleast_2d(np.asarray(frames, dtype=np.float32))
        if bounds is None:
            bounds = np.array([[0, frames.shape[0]]])
        with small_query_blas(frames.shape[0]):  # live mirror: a frame
            Fx = self.shape_.transform(frames)
            G = self.dynamics_.transform(Fx, bounds)
            return self.embedding_.transform(G)

    @property
    def inverse_map(self) -> InverseMap:
        """The Delaunay inverse map Y -> X, built on first use."""
        check_is_fitted(self, "Fy_")
        if getattr(self, "_inverse", None) is None:
            from engine.manifold.inverse import InverseMap

            self._inverse = InverseMap(n_dims=min(3, self.Fy_.shape[1])).fit(self.Fy_, self.Fx_)
        assert self._inverse is not None
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

    def save(self, path: str | os.PathLike[str], *, include_frames: bool | None = None) -> Path:
        """Write the fitted manifold (and its corpus) to one ``.npz`` file, atomically.

        ``include_frames=None`` stores the corpus frames when they take at most
        512 MiB; otherwise only F^x is stored and :meth:`load` reconstructs the frames
        as ``mean + F^x X^T`` (the shape space's filtered reconstruction). Frames read
        from a corpus stored in blocks (``engine.recordings.corpus_blocks``) are never copied
        (unless ``include_frames=True``): the file references that corpus file instead
        (:func:`engine.recordings.corpus_blocks.frames_reference`), and :meth:`load` reads the
        blocks from it.
        """
        from engine.recordings.frame_blocks import BlockFrames

        check_is_fitted(self, "Fy_")
        path = Path(path)
        reference: dict[str, Any] = {}
        if include_frames is None and isinstance(self.corpus_.frames, BlockFrames):
            from engine.recordings.corpus_blocks import frames_reference

            reference, include_frames = frames_reference(self.corpus_.frames, path), False
        if include_frames is None:
            include_frames = self.corpus_.frames.nbytes <= MAX_SAVED_FRAME_BYTES
        d = self.fitted_arrays()
        d.update(self.corpus_.to_arrays(include_frames=include_frames, base=path.resolve().parent))
        d.update(reference)
        with atomic_write(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, **d)
        return path

    def fitted_arrays(self) -> dict:
        """What the fit made, as the flat dict of arrays :meth:`save` writes beside the corpus's arrays
        (:meth:`from_arrays` reads it back)."""
        check_is_fitted(self, "Fy_")
        d = {"manifold_version": np.array(FILE_VERSION),
             "manifold_params": np.array(json.dumps(self.get_params())),
             "manifold_timings": np.array(json.dumps(self.timings_)),
             "Fx": self.Fx_, "Fxv": self.Fxv_, "G": self.G_, "Fy": self.Fy_}
        if getattr(self, "state_x_", None) is not None:
            d["state_x"] = self.state_x_
        if getattr(self, "synthesis_choice_", None) is not None:
            d["synthesis_choice"] = np.array(json.dumps(self.synthesis_choice_))
            if getattr(self, "synthesis_states_", None) is not None:
                d["synthesis_states"] = np.asarray(self.synthesis_states_, dtype=np.float64)
            d.update({f"synthesis_models/{k}": v for k, v in (getattr(self, "synthesis_models_", None) or {}).items()})
        for name, attr in self._PARTS.items():
            d.update(dump_estimator(getattr(self, attr), name))
        return d

    @classmethod
    def load(cls, path: str | os.PathLike[str], *, memory_map: bool | None = None) -> Manifold:
        """Read a manifold written by :meth:`save`, without refitting.

        ``memory_map``: None (default) leaves the large per-frame arrays (of at least
        ``engine.files.persist.MMAP_MIN_BYTES``) memory-mapped from the file, read-only, paged in
        as they are used; True maps every array the file stores uncompressed; False reads
        everything into memory. The checks below read mapped arrays a block at a time and
        give the pages back, so a check does not make the file resident.

        Every array is checked before use (see ``engine.files.validate``): dtypes, shapes
        that fit together (N frames, m shape components, k embedding dims, L reference
        points, K states), finiteness, index ranges (state labels < K, CSR indices
        within the matrix), and the saved parameters are parsed against each
        estimator's own parameters (unknown keys refused). Any fault raises
        :class:`ManifoldFileError` naming the file and the field.
        """
        path = Path(path)
        try:
            d = read_npz(path, memory_map=memory_map)
        except FileNotFoundError:
            raise ManifoldFileError(f"{path}: no such manifold file") from None
        except NpzReadError as exc:
            raise ManifoldFileError(f"{path}: not a readable .npz manifold file ({exc.reason})") from None
        return cls.from_arrays(d, source=path)

    @classmethod
    def from_arrays(cls, d: Mapping[str, Any], *, source: str | os.PathLike[str],
                    corpus: Corpus | None = None) -> Manifold:
        """A manifold from the arrays :meth:`save` writes (``d``: name -> ndarray), every one checked.

        ``corpus``: the corpus the manifold was fitted to, when ``d`` holds only what the fit made
        (:meth:`fitted_arrays`, the per-frame arrays the fit derives from the corpus included); its
        frame count must be the manifold's. ``source`` names the file in messages.

        Raises
        ------
        ManifoldFileError
            Any fault, naming ``source`` and the field.
        """
        from engine.files.validate import FieldError

        path = Path(source)
        if "manifold_version" not in d:
            hint = " (it is a corpus file: build it with 'lipspace build')" if "corpus_version" in d else ""
            raise ManifoldFileError(f"{path}: not a Lipspace manifold file{hint}")
        try:
            return read_fitted(cls, d, path, corpus, parts=cls._PARTS)
        except FieldError as exc:
            raise ManifoldFileError(str(exc)) from None
        except CorpusError as exc:
            msg = str(exc)
            raise ManifoldFileError(msg if msg.startswith(str(path)) else f"{path}: corpus part: {msg}") from None

def project_x(manifold: Manifold, Fx: ArrayLike) -> np.ndarray:
    """Out-of-sample F^y of one utterance-long trajectory given in X.

    The fitted manifold's own pipeline without its shape stage: velocities inside the
    trajectory (one utterance), the fitted dynamic features, the embedding's
    out-of-sample transform. ``project_x(m, m.shape_.transform(F))`` is ``m.project(F)``.

    Parameters
    ----------
    manifold : Manifold
        Fitted.
    Fx : ndarray of shape (n, m)
        Shape coordinates of consecutive frames of one utterance.

    Returns
    -------
    ndarray of shape (n, n_embedding), float32
    """
    Fx = np.atleast_2d(np.asarray(Fx, dtype=np.float32))
    G = manifold.dynamics_.transform(Fx, np.array([[0, Fx.shape[0]]]))
    return manifold.embedding_.transform(G)
