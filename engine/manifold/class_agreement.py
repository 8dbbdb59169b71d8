"""How well the four tangent classes agree with the lips' own aperture, and with the trivial rule.

The classes (:class:`engine.manifold.tangent.TangentFrames`) are statements about the lips: a
frame is *opening* when the lip aperture grows, *accelerating* when the aperture's
speed grows. This module measures those statements against the aperture itself:

* **opening**: the class against the sign of the aperture's central difference
  (a[i+1] - a[i-1]) / 2, over the frames where it changes by more than
  :data:`MOVING_PER_FRAME` (0.05 mm per frame) -- the frames that move;
* **accelerating**: the class against the sign of the change of the aperture's speed
  ``|da/dt|`` (central differences of the central differences), over the frames whose
  speed change is above the corpus's :data:`SPEED_QUANTILE` quantile.

Beside them it reports the **trivial rule**, the same two signs read off the measured
aperture directly (identical to the truth when the truth *is* the measured aperture;
on the synthetic talker the truth is its noise-free aperture and the rule reads the
noisy captured lips, like the method), and the **second-difference reading**: how
often the sign of the aperture's own central second difference, compared with the sign
of its central velocity, gives the speed change. It reads acceleration from the exact
aperture the way a class reads it from one step; where the aperture's velocity flips
sign between neighbouring frames (noise, or a frame rate too low for the movement) the
opening of one span and the speed change of a wider one disagree, and it falls well
below 100 %.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine.manifold.local_gradients import central_difference

__all__ = ["ClassAgreement", "class_agreement", "moving_frames", "MOVING_PER_FRAME", "SPEED_QUANTILE", "OPENING_BOUND",
           "ACCELERATING_BOUND"]

#: a frame "moves" when the aperture changes by more than this per frame (the aperture's unit, mm)
MOVING_PER_FRAME = 0.05
#: frames whose speed change is at or below this quantile of the corpus's are not scored for acceleration
SPEED_QUANTILE = 0.25
#: agreement below which ``lipspace info`` warns (opening, accelerating)
OPENING_BOUND = 0.95
ACCELERATING_BOUND = 0.85


@dataclass(frozen=True)
class ClassAgreement:
    """Agreement of the classes with the aperture (fractions in [0, 1], NaN when no frame qualifies)."""

    opening: float
    accelerating: float
    trivial_opening: float
    trivial_accelerating: float
    accelerating_second_difference: float
    n_opening: int
    n_accelerating: int

    def describe(self) -> str:
        """One line: method, trivial rule and second-difference reading, in percent."""
        return (f"opening {100 * self.opening:.1f}% of {self.n_opening} moving frames (trivial rule "
                f"{100 * self.trivial_opening:.1f}%), accelerating {100 * self.accelerating:.1f}% of "
                f"{self.n_accelerating} (trivial rule {100 * self.trivial_accelerating:.1f}%, the aperture's second "
                f"difference {100 * self.accelerating_second_difference:.1f}%)")


def _inner(bounds, n):
    """Frames with a frame on either side inside their utterance (central differences defined)."""
    ok = np.ones(n, bool)
    b = np.asarray(bounds, dtype=np.int64)
    ok[b[:, 0]] = False
    ok[b[:, 1] - 1] = False
    return ok


def _truth(a, bounds):
    """(velocity, speed change, moving frames, accelerating frames) of aperture ``a``."""
    n = len(a)
    v = central_difference(a, bounds)
    dspeed = central_difference(np.abs(v), bounds)
    inner = _inner(bounds, n)
    # the speed change needs the velocity's neighbours to be central differences too
    inner2 = inner & np.r_[False, inner[:-1]] & np.r_[inner[1:], False]
    moving = inner & (np.abs(v) > MOVING_PER_FRAME)
    scored = np.flatnonzero(inner2)
    accel_frames = np.zeros(n, bool)
    if scored.size:
        thr = np.quantile(np.abs(dspeed[scored]), SPEED_QUANTILE)
        accel_frames[scored] = np.abs(dspeed[scored]) > thr
    return v, dspeed, moving, accel_frames


def moving_frames(aperture, bounds) -> np.ndarray:
    """Frames whose aperture's central difference exceeds :data:`MOVING_PER_FRAME`, (N,) bool."""
    return _truth(np.asarray(aperture, dtype=np.float64), bounds)[2]


def _frac(hit, where):
    return float(np.mean(hit[where])) if where.any() else float("nan")


def class_agreement(opening, accelerating, aperture, bounds, *, measured=None) -> ClassAgreement:
    """Agreement of the opening / accelerating flags with the aperture (see the module notes).

    Parameters
    ----------
    opening, accelerating : bool ndarray of shape (N,)
        ``TangentFrames.opening_`` and ``accelerating_``.
    aperture : ndarray of shape (N,)
        The truth: the lip aperture (mm) per frame.
    bounds : int ndarray of shape (U, 2)
    measured : ndarray of shape (N,), optional
        The aperture the trivial rule reads (default: ``aperture``); on a synthetic
        talker, the aperture of its captured (noisy) lip points.

    Returns
    -------
    ClassAgreement
    """
    a = np.asarray(aperture, dtype=np.float64)
    op, acc = np.asarray(opening, bool), np.asarray(accelerating, bool)
    if op.shape != a.shape or acc.shape != a.shape:
        raise ValueError(f"opening, accelerating and aperture must have one value per frame; got "
                         f"{op.shape}, {acc.shape}, {a.shape}")
    v, dspeed, moving, accel_frames = _truth(a, bounds)
    up, faster = v > 0, dspeed > 0
    m = a if measured is None else np.asarray(measured, dtype=np.float64)
    mv = central_difference(m, bounds)
    trivial_up, trivial_faster = mv > 0, central_difference(np.abs(mv), bounds) > 0
    # the second difference over the same five frames the speed change spans
    second = central_difference(central_difference(a, bounds), bounds)
    one_step = np.sign(second) == np.sign(v)
    return ClassAgreement(
        opening=_frac(op == up, moving), accelerating=_frac(acc == faster, accel_frames),
        trivial_opening=_frac(trivial_up == up, moving), trivial_accelerating=_frac(trivial_faster == faster,
                                                                                    accel_frames),
        accelerating_second_difference=_frac(one_step == faster, accel_frames),
        n_opening=int(moving.sum()), n_accelerating=int(accel_frames.sum()))
