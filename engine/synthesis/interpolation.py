"""Direct interpolation of the phone targets in X: the "linear" and "cubic" baselines of synthesis.

They get the same targets as the manifold's methods (behind the same :class:`Synthesizer`
interface) and draw straight or spline paths between them in the shape space, ignoring the
state graph: the trivial baseline the manifold's paths are compared with.
"""
from __future__ import annotations

import numpy as np

from engine.constraints import StrOptions, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.phonetics.targets import TargetSequence
from engine.phonetics.targets import resolve_phone as _resolve_phone
from engine.synthesis.trajectory import Trajectory, interpolate_targets
from engine.synthesis.trajectory import check_fitted_manifold as _check_fitted_manifold
from engine.synthesis.trajectory import target_frames as _target_frames
from engine.threads import single_blas_thread

__all__ = ["InterpolationSynthesizer"]


class InterpolationSynthesizer(Estimator):
    """Direct interpolation of the phone targets in X ("linear" or "cubic" spline).

    A target's X is its oracle F^x when the target carries one, else the mean F^x of
    its phone's cluster (the mid-point frames of that phone in the training corpus).
    Outside the first and last target the value is held constant.

    Parameters
    ----------
    kind : {"linear", "cubic"}
        ``"cubic"`` uses :class:`scipy.interpolate.CubicSpline` (not-a-knot ends).
    """

    _parameter_constraints = {"kind": [StrOptions(("linear", "cubic"))]}

    def __init__(self, *, kind="linear"):
        self.kind = kind

    @property
    def method(self):
        return self.kind

    def fit(self, manifold):
        """Store the per-phone mean F^x of a fitted manifold's corpus."""
        validate_params(self)
        _check_fitted_manifold(manifold)
        mids, labels, *_ = manifold.corpus_.phone_table()
        labs, counts = np.unique(labels, return_counts=True)
        labs = labs[np.argsort(-counts, kind="stable")]  # most frequent first (stand-in phones)
        Fx = np.asarray(manifold.Fx_)
        self.phone_labels_ = [str(s) for s in labs]
        self.phone_means_ = (np.stack([Fx[mids[labels == lab]].mean(axis=0, dtype=np.float64) for lab in labs])
                             if labs.size else np.zeros((0, Fx.shape[1])))
        self.n_components_ = int(Fx.shape[1])
        return self

    def target_x(self, targets: TargetSequence, warnings=None) -> np.ndarray:
        """X of every target, ndarray of shape (T, m); phones the corpus lacks get a stand-in's mean."""
        check_is_fitted(self, "phone_means_")
        index = {lab: i for i, lab in enumerate(self.phone_labels_)}
        rows = []
        for t in targets.targets:
            if t.x is not None:
                x = np.asarray(t.x, dtype=np.float64).reshape(-1)
                if x.size != self.n_components_:
                    raise ValueError(f"target X has {x.size} components, the shape space {self.n_components_}")
                rows.append(x)
            else:
                rows.append(self.phone_means_[index[_resolve_phone(t.label, self.phone_labels_, warnings,
                                                                   "instances")]])
        return np.array(rows)

    @single_blas_thread
    def synthesize(self, targets: TargetSequence) -> Trajectory:
        check_is_fitted(self, "phone_means_")
        f = _target_frames(targets)
        warnings: list[str] = []
        X = self.target_x(targets, warnings)
        t = np.arange(targets.n_frames, dtype=np.float64)
        out = interpolate_targets(self.kind, f, X, targets.n_frames)
        return Trajectory(times=t / targets.rate, Fx=out.astype(np.float32), Fy=None, method=self.kind,
                          target_frames=f, target_labels=[x.label for x in targets.targets], warnings=warnings)
