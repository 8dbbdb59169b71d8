"""Synthesisers over the validated state model: the learnt manifold paths and the state-velocity Hermite spline.

Both fit an :class:`engine.synthesis.statepaths.StateModel` on a manifold's frames with the
settings a validation split chose (:func:`engine.synthesis.method_choice.choose_methods`), and
turn any :class:`engine.phonetics.targets.TargetSequence` into X:

* a target's state is that of its F^y point in the state model's dims; a target that
  carries only a state of the manifold's own (3-D) state graph -- a state clicked in the
  explorer -- stands at the mean F^y of that state's frames; targets with only a phone
  label get their states from the phone lattice (:meth:`StateModel.phone_states`);
* the protocol (:func:`engine.synthesis.method_choice.target_protocol`) decides whether the true X
  at the targets is used (``oracle``) and which validated weights the manifold method
  takes.

:class:`LearntPathSynthesizer` (method ``"manifold"``) is, per shape component, the
validated base interpolation through the targets (without validation data the spline
with velocities calibrated on the targets) plus the validated share of the training
paths between the states (:meth:`StateModel.learnt_x`); :class:`StateHermiteSynthesizer` (``"sv-hermite"``) the
spline alone.
"""
from __future__ import annotations

import numpy as np

from engine.constraints import validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.synthesis.learnt_paths import prior_blend
from engine.synthesis.trajectory import Trajectory, check_fitted_manifold, target_frames
from engine.threads import single_blas_thread

__all__ = ["LearntPathSynthesizer", "StateHermiteSynthesizer"]


class _StateModelSynthesizer(Estimator):
    """Shared fitting and target resolution; see the module docstring.

    Parameters
    ----------
    choice : dict or None
        Validated settings (:func:`engine.synthesis.method_choice.choose_methods`); None measures
        them (cached).
    """

    method = ""
    _parameter_constraints = {"choice": [dict, None]}

    def __init__(self, *, choice=None):
        self.choice = choice

    def fit(self, manifold, progress=None):
        from engine.synthesis.statepaths import StateModel

        validate_params(self)
        check_fitted_manifold(manifold)
        ch = self.choice
        if ch is None:
            from engine.synthesis.method_choice import choose_methods

            ch = choose_methods(manifold, progress=progress)
        self.choice_ = ch
        c = manifold.corpus_
        # every phone's mid-point frame and label: the corpus's phone table (built once, at once; a loop over the
        # phones took 6 s at a million frames), which is phone_mids of all its utterances
        phones = c.phone_table()[:2] if any(u.phones for u in c.utterances) else None
        from engine.synthesis.stored_choice import stored_states

        # the states a build fitted at these settings (the manifold file's), else K-means now
        self.model_ = StateModel(state_dims=int(ch["state_dims"]), n_states=ch.get("n_states"),
                                 n_neighbors=int(ch.get("n_neighbors", 40))).fit(
            manifold.Fy_, manifold.Fx_, manifold.Fxv_, c.bounds, phones=phones,
            centroids=stored_states(manifold, ch))
        g = manifold.states_
        lab = np.asarray(g.labels_)
        K = int(g.centroids_.shape[0])
        n = np.maximum(np.bincount(lab, minlength=K), 1)
        Fy = np.asarray(manifold.Fy_, dtype=np.float64)
        sums = [np.bincount(lab, weights=Fy[:, j], minlength=K) for j in range(Fy.shape[1])]
        self._graph_y = np.stack(sums, 1) / n[:, None]
        self._manifold = manifold
        return self

    def _states(self, targets, warnings):
        """(protocol, states (T,), X at the targets or None)."""
        from engine.synthesis.method_choice import target_protocol

        sm = self.model_
        d = int(sm.state_dims)
        fixed = []
        for t in targets.targets:
            if t.y is not None:
                y = np.asarray(t.y, dtype=np.float64).reshape(-1)
                if y.size < d:
                    raise ValueError(f"target at frame {t.frame}: its F^y point has {y.size} dims, the state model {d}")
                fixed.append(int(sm.predict(y[None, :d])[0]))
            elif t.state is not None:
                if not 0 <= int(t.state) < self._graph_y.shape[0]:
                    raise ValueError(f"target state {t.state} out of range 0..{self._graph_y.shape[0] - 1}")
                fixed.append(int(sm.predict(self._graph_y[int(t.state)][None, :d])[0]))
            else:
                fixed.append(None)
        protocol = target_protocol(targets)
        f = target_frames(targets)
        if any(s is None for s in fixed):
            states = sm.phone_states(f, targets.labels, warnings=warnings, fixed=fixed)
        else:
            states = np.asarray(fixed, dtype=np.int64)
        xt = np.array([t.x for t in targets.targets], dtype=np.float64) if protocol == "oracle" else None
        return protocol, states, xt

    def _x(self, protocol, f, states, n, xt):  # pragma: no cover - overridden
        raise NotImplementedError

    @single_blas_thread
    def synthesize(self, targets) -> Trajectory:
        check_is_fitted(self, "model_")
        warnings: list[str] = []
        f = target_frames(targets)
        protocol, states, xt = self._states(targets, warnings)
        X = self._x(protocol, f, states, targets.n_frames, xt)
        return Trajectory(times=np.arange(targets.n_frames) / targets.rate, Fx=X.astype(np.float32), Fy=None,
                          method=self.method, target_frames=f, target_labels=[t.label for t in targets.targets],
                          warnings=warnings, info={"protocol": protocol, "states": states.tolist()})


class LearntPathSynthesizer(_StateModelSynthesizer):
    """The manifold synthesis: a validated base through the targets plus the validated share of the learnt paths."""

    method = "manifold"

    def _x(self, protocol, f, states, n, xt):

        w = (self.choice_.get("blend") or {}).get(protocol)
        if w is None:  # a protocol the validation did not measure (e.g. phones on a corpus without them)
            w = prior_blend(self.model_.inverse_.means_.shape[1])
        return self.model_.learnt_x(f, states, n, w, x_targets=xt)


class StateHermiteSynthesizer(_StateModelSynthesizer):
    """The state-velocity Hermite spline through the target states (or the true X) with their mean velocities."""

    method = "sv-hermite"

    def _x(self, protocol, f, states, n, xt):
        return self.model_.hermite_x(f, states, n, xt)
