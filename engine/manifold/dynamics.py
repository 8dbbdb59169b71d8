"""Dynamic features G = [alpha (F^x - mu), beta (F^x' - mu')] (paper section 3.1).

Velocities never cross an utterance boundary: inside each utterance
F^x'_i = F^x_i - F^x_{i-1}, and the first frame uses F^x_1 - F^x_0. Each block is
centred on its mean and scaled by **one scalar** so that its largest absolute entry
is 1; per-component scaling would break the dominance of component 1 that the
manifold's structure relies on.

One frame can set that scalar: a tracking glitch with a huge velocity shrinks the
whole velocity block. ``scale="p99"`` (or any ``"pQ"``) scales each block by the Q-th
percentile of its absolute entries instead, and a :class:`DynamicScaleWarning` says
when a block's maximum lies more than :data:`OUTLIER_RATIO` times above the 99th
percentile of its column (measured ratios on clean data: 1.5-2.2 on the synthetic
talkers and the Haskins pair).
"""
from __future__ import annotations

import re
import warnings

import numpy as np

from engine.constraints import Condition, StrOptions, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.recordings.bounds import velocities
from engine.recordings.corpus import CorpusWarning

__all__ = ["DynamicFeatures", "DynamicScaleWarning", "OUTLIER_RATIO", "SCALES"]

#: a block whose largest absolute entry exceeds its 99th percentile by more than this warns
OUTLIER_RATIO = 4.0


class DynamicScaleWarning(CorpusWarning):
    """A few extreme frames dominate the scale of a block of G (shape or velocity)."""


def _percentile(scale) -> float | None:
    """Q of a scale ``"pQ"`` (None when ``scale`` is not one)."""
    m = re.fullmatch(r"p(\d+(?:\.\d+)?)", scale) if isinstance(scale, str) else None
    return None if m is None else float(m.group(1))


#: the constraint of a block scale (:class:`DynamicFeatures` ``scale``, :class:`engine.manifold.model.Manifold`
#: ``dynamics_scale``): "max" or a percentile "pQ" with 50 <= Q <= 100
SCALES = [StrOptions({"max"}),
          Condition(lambda s: 50 <= _percentile(s) <= 100,  # type: ignore[operator]  # None raises: refused
                    "a percentile 'pQ' with 50 <= Q <= 100 (e.g. 'p99')",
                    bad=["p200", "p10", "q99"])]


def _scale_quantile(scale) -> float | None:
    """None for "max", else the percentile (0, 100] of ``"pQ"`` (a scale :data:`SCALES` accepts)."""
    return None if scale == "max" else _percentile(scale)


class DynamicFeatures(Estimator):
    """Scaled shape + velocity features.

    Parameters
    ----------
    scale : str, default="max"
        How each block's scalar is set: ``"max"`` (the paper: largest absolute entry
        becomes 1) or ``"pQ"`` (e.g. ``"p99"``: the Q-th percentile of the absolute
        entries becomes 1, robust to a few outlying frames).

    Attributes
    ----------
    mean_ : ndarray of shape (m,)
        mu, mean of F^x.
    velocity_mean_ : ndarray of shape (m,)
        mu', mean of F^x'.
    alpha_, beta_ : float
        Scalars making ``max |alpha (F^x - mu)| = 1`` and ``max |beta (F^x' - mu')| = 1``
        (with ``scale="pQ"``: the Q-th percentiles equal 1).
    shape_outlier_ratio_, velocity_outlier_ratio_ : float
        Per block: the largest absolute entry / the 99th percentile of the column that holds it.
    """

    _parameter_constraints = {"scale": SCALES}

    #: fitted attributes a manifold file stores and checks on load, as
    #: :func:`engine.files.persist.load_estimator` specs (shape symbols shared across the file: m shape
    #: components)
    _persisted_attributes = {
        "mean_": dict(kind="array", dtype="float", shape=("m",)),
        "velocity_mean_": dict(kind="array", dtype="float", shape=("m",)),
        "alpha_": dict(kind="float"),
        "beta_": dict(kind="float"),
    }

    def __init__(self, *, scale="max"):
        self.scale = scale

    def fit(self, Fx, bounds):
        """Fit mu, mu', alpha, beta from F^x (N, m) and utterance bounds (U, 2)."""
        validate_params(self)
        Fx = np.asarray(Fx, dtype=np.float32)
        if Fx.ndim != 2 or Fx.shape[0] < 2:
            raise ValueError(f"F^x must be (N >= 2, m), got shape {Fx.shape}; pass at least 2 frames")
        V = velocities(Fx, bounds)
        self.mean_ = Fx.mean(axis=0, dtype=np.float64).astype(np.float32)
        self.velocity_mean_ = V.mean(axis=0, dtype=np.float64).astype(np.float32)
        q = _scale_quantile(self.scale)
        ax = av = 0.0
        for name, A in (("shape", np.abs(Fx - self.mean_)), ("velocity", np.abs(V - self.velocity_mean_))):
            # against the column that holds the maximum: many quiet components would
            # otherwise pull a block-wide percentile down and flag clean data
            j = int(np.unravel_index(np.argmax(A), A.shape)[1])
            mx, p99 = float(A.max()), float(np.percentile(A[:, j], 99))
            ratio = mx / p99 if p99 > 0 else float("inf") if mx > 0 else 1.0
            setattr(self, f"{name}_outlier_ratio_", float(ratio))
            if ratio > OUTLIER_RATIO:
                hint = ("" if q is not None else
                        "; a percentile scale (lipspace build --dynamics-scale p99) is robust to them")
                warnings.warn(f"the {name} block of G: its largest |entry| {mx:.4g} is {ratio:.1f} x its 99th "
                              f"percentile {p99:.4g} (more than {OUTLIER_RATIO:g} x): a few extreme frames "
                              f"(tracking glitches?) set the scale{hint}", DynamicScaleWarning, stacklevel=2)
            s = mx if q is None else float(np.percentile(A, q))
            if name == "shape":
                ax = s
            else:
                av = s
        lengths = np.diff(np.asarray(bounds, dtype=np.int64).reshape(-1, 2), axis=1).ravel()
        if lengths.size and lengths.max() < 2:
            raise ValueError(f"every utterance holds a single frame ({lengths.size} utterances): a velocity needs "
                             "at least 2 consecutive frames of one utterance")
        if ax == 0:
            raise ValueError("the lip shape never changes in this corpus (every frame is the same shape); "
                             "nothing to embed")
        if av == 0:
            raise ValueError("the lips never move within an utterance of this corpus (no velocity); nothing to "
                             "embed")
        self.alpha_ = 1.0 / ax
        self.beta_ = 1.0 / av
        return self

    def transform_pair(self, Fx, Fxv) -> np.ndarray:
        """G from shape and velocity: ndarrays (n, m) each -> (n, 2m) float32."""
        check_is_fitted(self, "alpha_")
        Fx = np.asarray(Fx, dtype=np.float32)
        Fxv = np.asarray(Fxv, dtype=np.float32)
        m = self.mean_.shape[0]
        if Fx.shape != Fxv.shape or Fx.ndim != 2 or Fx.shape[1] != m:
            raise ValueError(f"F^x and F^x' must both be (n, {m}); got {Fx.shape} and {Fxv.shape}")
        return np.hstack([np.float32(self.alpha_) * (Fx - self.mean_),
                          np.float32(self.beta_) * (Fxv - self.velocity_mean_)])

    def transform(self, Fx, bounds) -> np.ndarray:
        """G for frames F^x (N, m) with utterance bounds (U, 2) -> (N, 2m)."""
        check_is_fitted(self, "alpha_")
        return self.transform_pair(Fx, velocities(Fx, bounds))
