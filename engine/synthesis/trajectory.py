"""What every synthesis method shares: the synthesised :class:`Trajectory`, the
:class:`Synthesizer` protocol, the checks of a fitted manifold and of the target
frames, the Gaussian smoothing of a path along its frames and the direct
interpolation of target X (:func:`interpolate_targets`).

:mod:`engine.synthesis.viterbi` (the paper's method), :mod:`engine.synthesis.interpolation` (the
interpolation baselines), :mod:`engine.synthesis.unitselection` (the unit-selection baseline) and
:mod:`engine.synthesis.statepaths` all import from here, so none of them imports another for these helpers.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from engine.constraints import HasMethods, validate_params
from engine.estimator import Estimator, check_is_fitted, clone

if TYPE_CHECKING:
    from collections.abc import Sequence

    from engine.manifold.model import Manifold
    from engine.phonetics.targets import TargetSequence
    from engine.recordings.corpus import Corpus, PhoneInterval, Utterance

__all__ = ["phone_mids", "Trajectory", "Synthesizer", "check_fitted_manifold", "target_frames", "smooth",
           "phone_sequences", "PhoneModelSynthesizer", "interpolate_targets", "INTERPOLATIONS"]

#: kinds of :func:`interpolate_targets`
INTERPOLATIONS = ("linear", "cubic", "pchip", "hermite")


@dataclass
class Trajectory:
    """A synthesised lip trajectory.

    Attributes
    ----------
    times : ndarray of shape (n,)
        Seconds of each frame from the start.
    Fx : ndarray of shape (n, m), float32
        Shape coordinates.
    Fy : ndarray of shape (n, state_dims) or None
        Embedding coordinates (methods that move in Y: the state centroids).
    method : str
    states : ndarray of shape (n,) int or None
        State path (manifold method).
    target_frames : ndarray of shape (T,) int
    target_labels : list of str
    warnings : list of str
        Targets missed, fall-backs taken.
    info : dict
        Method-specific details (e.g. the units and joins of unit selection).
    """

    times: np.ndarray
    Fx: np.ndarray
    Fy: np.ndarray | None
    method: str
    states: np.ndarray | None = None
    target_frames: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    target_labels: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    info: dict = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        return int(self.Fx.shape[0])

    def frames(self, manifold: Manifold) -> np.ndarray:
        """Frames (n, C) reconstructed through the manifold's shape space."""
        return manifold.shape_.inverse_transform(self.Fx)


@runtime_checkable
class Synthesizer(Protocol):
    """Anything that turns a :class:`engine.phonetics.targets.TargetSequence` into a :class:`Trajectory`."""

    def synthesize(self, targets: TargetSequence) -> Trajectory:  # pragma: no cover - protocol
        ...


def check_fitted_manifold(manifold: Any) -> None:
    """ValueError naming the first missing attribute unless ``manifold`` is a fitted Manifold."""
    for attr in ("Fy_", "Fx_", "states_", "shape_", "corpus_"):
        if not hasattr(manifold, attr):
            raise ValueError(f"synthesis needs a fitted engine.manifold.model.Manifold (missing {attr}); "
                             "call fit first")


def target_frames(targets: TargetSequence) -> np.ndarray:
    """Frames (T,) int64 of the targets; ValueError when none, out of 0..n_frames-1 or not increasing."""
    f = np.array([t.frame for t in targets.targets], dtype=np.int64)
    if f.size == 0:
        raise ValueError("no targets to synthesise from")
    if f.min() < 0 or f.max() >= targets.n_frames:
        raise ValueError(f"target frames {f.min()}..{f.max()} fall outside 0..{targets.n_frames - 1}")
    bad = np.flatnonzero(np.diff(f) <= 0)
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"targets {i} ({targets.targets[i].label!r}) and {i + 1} "
                         f"({targets.targets[i + 1].label!r}) are both at frame {f[i]} or out of order "
                         f"(frame {f[i + 1]}): a gap needs at least one frame; lengthen the phones")
    return f


def smooth(A: ArrayLike, sigma: float) -> np.ndarray:
    """Gaussian smoothing along frames (axis 0) with s.d. ``sigma`` frames (0: unchanged).

    ``A`` is (n, m); returns (n, m) float64.
    """
    A = np.asarray(A, dtype=np.float64)
    if float(sigma) < 0:
        raise ValueError(f"smoothing sigma must be >= 0 frames, got {sigma}")
    if float(sigma) == 0 or A.shape[0] < 2:
        return A
    from scipy.ndimage import gaussian_filter1d  # 0.1 s to import: paid only where a method smooths

    return gaussian_filter1d(A, float(sigma), axis=0, mode="nearest")


def interpolate_targets(kind: str, frames: ArrayLike, X_targets: ArrayLike, n_frames: int,
                        velocities: ArrayLike | None = None) -> np.ndarray:
    """Trajectory (n_frames, m) through target X at ``frames`` by ``kind`` in :data:`INTERPOLATIONS`.

    ``"linear"``, ``"cubic"`` (:class:`scipy.interpolate.CubicSpline`, not-a-knot ends),
    ``"pchip"`` (shape-preserving monotone cubic) or ``"hermite"`` (cubic Hermite with
    the given ``velocities`` (T, m), in X per frame). With one target every kind is
    constant, with two ``"cubic"`` and ``"pchip"`` are linear. Before the first target
    the first is held, after the last the last.
    """
    from scipy.interpolate import CubicHermiteSpline, CubicSpline, PchipInterpolator

    if kind not in INTERPOLATIONS:
        raise ValueError(f"unknown interpolation {kind!r}; choose from {', '.join(INTERPOLATIONS)}")
    f = np.asarray(frames, dtype=np.float64)
    Xt = np.asarray(X_targets, dtype=np.float64)
    t = np.clip(np.arange(int(n_frames), dtype=np.float64), f[0], f[-1])
    if f.size == 1:
        return np.repeat(Xt[:1], t.size, axis=0)
    if kind == "linear" or (kind in ("pchip", "cubic") and f.size < 3):
        return np.column_stack([np.interp(t, f, Xt[:, j]) for j in range(Xt.shape[1])])
    if kind == "cubic":
        return CubicSpline(f, Xt, axis=0)(t)
    if kind == "pchip":
        return PchipInterpolator(f, Xt, axis=0)(t)
    if velocities is None:
        raise ValueError("hermite interpolation needs a velocity per target")
    return CubicHermiteSpline(f, Xt, np.asarray(velocities, dtype=np.float64), axis=0)(t)


def phone_sequences(utterances: Sequence[Utterance],
                    Fx: np.ndarray) -> list[tuple[np.ndarray, tuple[PhoneInterval, ...]]]:
    """(X (n, m) float64, phones) of each utterance with phones; ``Fx`` holds the corpus's rows."""
    return [(np.asarray(Fx[u.start:u.stop], dtype=np.float64), tuple(u.phones)) for u in utterances if u.phones]


class PhoneModelSynthesizer(Estimator):
    """A model of shape from phones and their times behind the :class:`Synthesizer` interface.

    Parameters
    ----------
    model : estimator
        With ``fit(sequences, rate)`` (sequences: (X, phones) per utterance) and
        ``predict(phones, n_frames, rate, warnings)`` (:class:`engine.synthesis.dominance.DominanceModel`,
        :class:`engine.synthesis.sliding_window.SlidingWindowRegressor`).
    method : str
        The method's name in the trajectories it makes.

    ``fit(manifold)`` fits a copy of ``model`` on the manifold's corpus (its phones and
    F^x); ``synthesize(targets)`` uses only ``targets.phones`` and the frame count.
    """

    _parameter_constraints = {"model": [HasMethods(("fit", "predict"))], "method": [str]}

    def __init__(self, *, model: Any, method: str) -> None:
        self.model = model
        self.method = method

    def fit(self, manifold: Manifold) -> PhoneModelSynthesizer:
        from engine.synthesis.stored_choice import stored_model

        validate_params(self)
        check_fitted_manifold(manifold)
        c = manifold.corpus_
        # the model a build fitted with these settings (stored in the manifold file), else fitted now
        stored = stored_model(manifold, self.method, self.model)
        self.model_ = stored if stored is not None else clone(self.model).fit(
            phone_sequences(c.utterances, manifold.Fx_), c.rate)
        return self

    def synthesize(self, targets: TargetSequence) -> Trajectory:
        check_is_fitted(self, "model_")
        warnings: list[str] = []
        X = self.model_.predict(targets.phones, targets.n_frames, targets.rate, warnings)
        f = target_frames(targets) if targets.targets else np.zeros(0, dtype=np.int64)
        return Trajectory(times=np.arange(targets.n_frames) / targets.rate, Fx=np.asarray(X, np.float32), Fy=None,
                          method=self.method, target_frames=f, target_labels=[t.label for t in targets.targets],
                          warnings=warnings)


def phone_mids(corpus: Corpus, utts: Sequence[Utterance]) -> tuple[np.ndarray, np.ndarray]:
    """(mid-point frames into the concatenated rows of ``utts``, labels) of their phones."""
    mids, labels, off = [], [], 0
    for u in utts:
        for p in u.phones:
            mids.append(off + corpus.time_to_frame(u, p.mid) - u.start)
            labels.append(p.label)
        off += u.n_frames
    return np.array(mids, dtype=np.int64), np.array(labels, dtype=str)
