"""Head-pose removal for landmarks tracked in video: a similarity Procrustes fit of rigid
reference landmarks to a per-speaker template, in millimetres.

A camera sees the head turn, move and come nearer (larger in the image). Each frame's
reference landmarks (forehead, nose bridge, temples, eye corners: they move with the
skull, not with speech) are fitted to the template by rotation, translation and one
isotropic scale (Umeyama's least-squares similarity); the same transform applied to the
lip landmarks leaves only lip movement. The template is the mean reference shape over
the speaker's frames, found iteratively (generalised Procrustes: align every frame to
the current template, average, repeat), then put in a canonical frame and scaled to mm:

* origin at the midpoint of the two eye centres (each the midpoint of an eye's corners);
* x from the eye on the image's left to the eye on its right, y up (toward the forehead),
  z toward the camera;
* the distance between the eye centres is ``interocular_mm`` (63 mm by default, the
  mean adult interpupillary distance): a stated assumption, not a measurement.
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np

from engine.constraints import Condition, Interval, validate_params
from engine.estimator import Estimator, check_is_fitted

__all__ = ["similarity_fit", "HeadPose", "DEFAULT_INTEROCULAR_MM", "check_interocular"]

#: mean adult interpupillary distance (mm), the default scale assumption
DEFAULT_INTEROCULAR_MM = 63.0


def similarity_fit(A, B):
    """Least-squares similarity transforms taking each ``A[n]`` onto ``B`` (Umeyama 1991).

    Parameters
    ----------
    A : ndarray of shape (N, P, 3) or (P, 3)
        Source point sets.
    B : ndarray of shape (P, 3)
        Target points.

    Returns
    -------
    s : ndarray (N,), R : ndarray (N, 3, 3), t : ndarray (N, 3)
        ``s[n] * A[n] @ R[n].T + t[n]`` is the best fit of ``A[n]`` to ``B`` (proper rotations).
    """
    A = np.asarray(A, dtype=np.float64)
    single = A.ndim == 2
    if single:
        A = A[None]
    B = np.asarray(B, dtype=np.float64)
    ma = A.mean(axis=1)
    mb = B.mean(axis=0)
    A0 = A - ma[:, None]
    B0 = B - mb
    H = np.einsum("npi,pj->nij", A0, B0)  # cross-covariance per frame
    U, S, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(np.einsum("nij,njk->nik", U, Vt)))
    D = np.ones((len(A), 3))
    D[:, 2] = d
    R = np.einsum("nji,nj,nkj->nik", Vt, D, U)  # R = V diag(D) U^T
    var_a = (A0 ** 2).sum(axis=(1, 2))
    s = (S * D).sum(axis=1) / np.maximum(var_a, 1e-300)
    t = mb - s[:, None] * np.einsum("nij,nj->ni", R, ma)
    return s, R, t


def check_interocular(value) -> float:
    """``value`` as a float when it is a plausible eye-centre distance in mm, else ValueError."""
    try:
        iod = float(value)
    except (TypeError, ValueError):
        iod = float("nan")
    if not np.isfinite(iod) or not 10.0 <= iod <= 200.0:
        raise ValueError(f"interocular_mm={value!r} (--interocular-mm): expected the distance between the eye "
                         f"centres in mm, between 10 and 200 (adults average {DEFAULT_INTEROCULAR_MM:g})")
    return iod


def _apply(s, R, t, X):
    return s[:, None, None] * np.einsum("nij,npj->npi", R, X) + t[:, None]


class HeadPose(Estimator):
    """Per-speaker reference template and per-frame similarity head-pose removal.

    Parameters
    ----------
    interocular_mm : float, default 63.0
        Assumed distance between the eye centres (mm); sets the scale of the output.
    eye_points : tuple of two pairs of int
        Positions (in the reference array) of the corners of the eye on the image's
        left and of the eye on its right.
    up_point : int
        Position of a forehead point (gives the up direction).
    n_iter : int, default 5
        Generalised-Procrustes iterations for the template.

    Attributes
    ----------
    template_ : ndarray (R, 3)
        Mean reference shape, canonical frame, mm.
    residual_mm_ : float
        RMS distance (mm) of the aligned reference landmarks from the template over the
        fitted frames (how rigid the fit found the head).
    n_frames_ : int
    """

    _parameter_constraints = {
        "interocular_mm": [Interval(Real, 10, 200, closed="both")],
        "eye_points": [Condition(lambda e: len(e) == 2 and all(len(p) == 2 for p in e)
                                 and all(isinstance(i, Integral) and not isinstance(i, bool) and int(i) >= 0
                                         for p in e for i in p),
                                 "two pairs of point positions (integers >= 0)", bad=[(13, 14), ((13, 14),)])],
        "up_point": [Interval(Integral, 0, None, closed="left")],
        "n_iter": [Interval(Integral, 1, None, closed="left")],
    }

    def __init__(self, *, interocular_mm: float = DEFAULT_INTEROCULAR_MM, eye_points=((13, 14), (16, 15)),
                 up_point: int = 0, n_iter: int = 5):
        self.interocular_mm = interocular_mm
        self.eye_points = eye_points
        self.up_point = up_point
        self.n_iter = n_iter

    def _canonical(self, T):
        (a, b), (c, d) = self.eye_points
        e1 = (T[a] + T[b]) / 2
        e2 = (T[c] + T[d]) / 2
        mid = (e1 + e2) / 2
        x = e2 - e1
        dist = float(np.linalg.norm(x))
        x /= dist
        up = T[self.up_point] - mid
        y = up - (up @ x) * x
        y /= np.linalg.norm(y)
        z = np.cross(x, y)
        R = np.stack([x, y, z])
        return (T - mid) @ R.T * (float(self.interocular_mm) / dist)

    def fit(self, ref):
        """Fit the template to reference landmarks of the speaker's frames.

        Parameters
        ----------
        ref : ndarray of shape (N, R, 3)
            Reference landmarks per frame (any units, any pose), N >= 1.

        Returns
        -------
        self
        """
        validate_params(self)
        ref = np.asarray(ref, dtype=np.float64)
        if ref.ndim != 3 or ref.shape[0] < 1 or ref.shape[2] != 3 or ref.shape[1] < 3:
            raise ValueError(f"reference landmarks of shape {ref.shape}; expected (frames >= 1, points >= 3, 3)")
        if not np.isfinite(ref).all():
            raise ValueError("reference landmarks hold NaN or inf; pass only frames where the face was found")
        T = self._canonical(ref[0])
        for _ in range(int(self.n_iter)):
            s, R, t = similarity_fit(ref, T)
            T = self._canonical(_apply(s, R, t, ref).mean(axis=0))
        s, R, t = similarity_fit(ref, T)
        resid = _apply(s, R, t, ref) - T
        self.template_ = T
        self.residual_mm_ = float(np.sqrt((resid ** 2).sum(axis=2).mean()))
        self.n_frames_ = int(ref.shape[0])
        return self

    def transform(self, ref, points):
        """Remove head pose: ``points`` of each frame moved by its reference fit to the template.

        Parameters
        ----------
        ref : ndarray of shape (N, R, 3)
            Reference landmarks per frame.
        points : ndarray of shape (N, P, 3)
            Landmarks to move (the lips), same frames.

        Returns
        -------
        ndarray of shape (N, P, 3), float64, mm in the template's canonical frame
        """
        check_is_fitted(self, "template_")
        ref = np.asarray(ref, dtype=np.float64)
        points = np.asarray(points, dtype=np.float64)
        if ref.ndim != 3 or ref.shape[1:] != self.template_.shape:
            raise ValueError(f"reference landmarks of shape {ref.shape}; expected (frames, "
                             f"{self.template_.shape[0]}, 3) like the template")
        if points.ndim != 3 or points.shape[0] != ref.shape[0] or points.shape[2] != 3:
            raise ValueError(f"points of shape {points.shape}; expected ({ref.shape[0]}, points, 3)")
        s, R, t = similarity_fit(ref, self.template_)
        return _apply(s, R, t, points)
