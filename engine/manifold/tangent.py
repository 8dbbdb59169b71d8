"""Tangent frames of the manifold and the four movement classes (paper section 3.2).

The paper gives every frame a local frame: s_i, the direction of maximum change in
lip shape from closed to open, and v_i, the direction of maximum change in velocity,
and classifies each step z_i of the trajectory by the signs of z_i . s_i and z_i . v_i:
opening or closing, accelerating or decelerating.

Here s_i and v_i are exactly those directions, measured: the local gradients over
F^y (all its dimensions) of the **opening** (the lip aperture when the corpus names
its lips; otherwise the first shape component stands in) and of the opening's
velocity, each fitted to the movements through frame i's neighbourhood
(:mod:`engine.manifold.local_gradients`, which also chooses the neighbourhood size for the
corpus). Both point the way their quantity grows, so they are oriented alike on every
corpus: +s_i opens the lips, +v_i speeds the opening up (or slows the closing).

The step z_i is the trajectory's **central** step (F^y_{i+1} - F^y_{i-1}) / 2, the
derivative of the trajectory at frame i (one-sided at an utterance's ends). The
paper's consecutive offset is the derivative half a frame later; at video rates that
half frame turns the class of many frames (see docs/METHOD.md, "Tangent frames").

* opening       iff z_i . s_i > 0 (the opening grows along the step),
* accelerating  iff sign(z_i . v_i) == sign(z_i . s_i) (its speed grows: the velocity
  grows while opening, or falls further below zero while closing).

``velocity_`` holds z_i . g_i with the unnormalised gradient g_i: the opening
velocity read on the manifold, in the opening's unit per second; it is the V
coordinate of the figures, so opening frames lie at V > 0 by construction.

For the 3-D picture (Y1-3) the global directions S and V are the frames' own s_i and
v_i averaged, and the zero-velocity plane passes through the slowest frames with V
as its normal; they are drawn, not used to classify.
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np

from engine.constraints import Interval, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.manifold.local_gradients import central_difference, local_gradients, neighbor_candidates, select_neighbors
from engine.recordings.bounds import check_bounds

__all__ = ["TangentFrames", "CLASS_NAMES", "NO_STEP", "DRAWN_DIMS"]

#: names of ``classes_`` 0..3
CLASS_NAMES = ("opening/accelerating", "opening/decelerating", "closing/accelerating", "closing/decelerating")
#: class of a frame with no step (an utterance of one frame)
NO_STEP = -1
#: dimensions of Y the global frame and the zero-velocity plane are drawn in
DRAWN_DIMS = 3
#: leading dims of F^y compared by the validation when ``n_dims`` is None (besides all of them)
DIM_CANDIDATES = (10,)


def _unit(x):
    n = np.linalg.norm(x, axis=-1, keepdims=True)
    return x / np.where(n > 0, n, 1.0), n[..., 0]


def _finite(name, a, n_rows=None):
    bad = ~np.isfinite(a).reshape(len(a), -1).all(axis=1)
    if bad.any():
        raise ValueError(f"{name} holds NaN or infinite values (first at frame {int(np.flatnonzero(bad)[0])}); "
                         "remove or repair those frames")
    if n_rows is not None and len(a) != n_rows:
        raise ValueError(f"{name} has {len(a)} frames but F^y has {n_rows}; pass arrays of the same corpus")
    return a


class TangentFrames(Estimator):
    """Local tangent frames, the four movement classes and the drawn global frame.

    Parameters
    ----------
    n_neighbors : int or None, default=None
        Frames (the frame itself included) each local gradient is fitted to. None:
        chosen for the corpus by held-out validation among
        :func:`engine.manifold.local_gradients.neighbor_candidates` (``n_neighbors_`` says
        which, ``neighbor_scores_`` how each did).
    n_dims : int or None, default=None
        Leading columns of F^y the frames live in. None: all of them or the first
        :data:`DIM_CANDIDATES`, whichever the validation prefers (``n_dims_``).
    zero_velocity_quantile : float, default=0.1
        Fraction of frames, those with the smallest opening speed, through whose mean
        the drawn zero-velocity plane passes.
    random_state : int, default=0
        Seed of the validation's held-out frames and, above
        :data:`engine.manifold.local_gradients.MAX_ANCHORS` frames, of the anchors.

    Attributes
    ----------
    n_dims_ : int
    n_neighbors_ : int
    neighbor_scores_ : ndarray of shape (n_candidates, 4)
        ``[dims, k, opening, acceleration]`` held-out agreement per candidate (no rows
        when both ``n_neighbors`` and ``n_dims`` were given).
    n_anchors_ : int
        Frames the gradients were fitted at (all of them up to ``MAX_ANCHORS``).
    s_, v_ : ndarray of shape (N, ``n_dims_``), float32
        Unit local shape and velocity directions.
    step_ : ndarray of shape (N, ``n_dims_``), float32
        Central steps z_i.
    velocity_ : ndarray of shape (N,), float32
        z_i . grad(opening): the opening velocity read on the manifold (opening unit / s).
    acceleration_ : ndarray of shape (N,), float32
        z_i . grad(opening velocity) (opening unit / s^2).
    opening_, accelerating_ : ndarray of shape (N,), bool
        False where there is no step.
    classes_ : ndarray of shape (N,), int8
        0 opening/accelerating, 1 opening/decelerating, 2 closing/accelerating,
        3 closing/decelerating, -1 (``NO_STEP``) in utterances of one frame.
    shape_direction_, velocity_direction_ : ndarray of shape (``n_dims_``,)
        Global S and V: the unit mean of the local s_i (v_i).
    S_, plane_normal_, plane_point_ : ndarray of shape (3,)
        The global frame drawn in Y1-3: S, and V as the normal of the zero-velocity
        plane through ``plane_point_`` (S orthogonal to V).
    n_degenerate_ : int
        Frames whose gradient could not be estimated (no movement around them) and
        took the global direction instead.
    opening_source_ : str
        What opening is: ``"lip aperture"`` or the stand-in named by the caller.
    opening_unit_ : str
        Its unit (``"mm"``; ``""`` for a stand-in without one).
    shape_coordinate_ : ndarray of shape (N,), float32
        The opening per frame: the S coordinate of the figures (``velocity_`` is V).
    """

    CLASS_NAMES = CLASS_NAMES

    _parameter_constraints = {
        "n_neighbors": [Interval(Integral, 3, None, closed="left"), None],
        "n_dims": [Interval(Integral, 1, None, closed="left"), None],
        "zero_velocity_quantile": [Interval(Real, 0, 1, closed="neither")],
        "random_state": ["random_state"],
    }

    #: fitted attributes a manifold file stores and checks on load, as
    #: :func:`engine.files.persist.load_estimator` specs (shape symbols shared across the file: N frames,
    #: t dims of the frames)
    _persisted_attributes = {
        "plane_point_": dict(kind="array", dtype="float", shape=(3,)),
        "plane_normal_": dict(kind="array", dtype="float", shape=(3,)),
        "S_": dict(kind="array", dtype="float", shape=(3,)),
        "shape_direction_": dict(kind="array", dtype="float", shape=("t",)),
        "velocity_direction_": dict(kind="array", dtype="float", shape=("t",)),
        "s_": dict(kind="array", dtype="float", shape=("N", "t")),
        "v_": dict(kind="array", dtype="float", shape=("N", "t")),
        "step_": dict(kind="array", dtype="float", shape=("N", "t")),
        "velocity_": dict(kind="array", dtype="float", shape=("N",)),
        "acceleration_": dict(kind="array", dtype="float", shape=("N",)),
        "opening_": dict(kind="array", dtype="bool", shape=("N",)),
        "accelerating_": dict(kind="array", dtype="bool", shape=("N",)),
        "classes_": dict(kind="array", dtype="int", shape=("N",), low=NO_STEP, high=len(CLASS_NAMES)),
        "shape_coordinate_": dict(kind="array", dtype="float", shape=("N",)),
        "opening_source_": dict(kind="str"),
        "opening_unit_": dict(kind="str"),
        "n_dims_": dict(kind="int", low=1),
        "n_neighbors_": dict(kind="int", low=1),
    }

    def __init__(self, *, n_neighbors=None, n_dims=None, zero_velocity_quantile=0.1, random_state=0):
        self.n_neighbors = n_neighbors
        self.n_dims = n_dims
        self.zero_velocity_quantile = zero_velocity_quantile
        self.random_state = random_state

    # ------------------------------------------------------------------ input
    def _check_params(self, n_cols):
        validate_params(self)
        if self.n_dims is not None and self.n_dims > n_cols:
            raise ValueError(f"n_dims={self.n_dims} but F^y has {n_cols} columns; lower n_dims or pass None")

    def _as_y(self, Y, name="Y") -> np.ndarray:
        Y = np.asarray(Y)
        if Y.ndim == 1:
            Y = Y[None, :]
        if Y.ndim != 2:
            raise ValueError(f"{name} must be a 2-D (frames, dims) array, got shape {Y.shape}")
        return Y

    # -------------------------------------------------------------------- fit
    def fit(self, Fy, bounds, opening, *, rate, source="lip aperture", unit="mm", executor=None):
        """Fit the local frames, classify every frame and place the drawn global frame.

        Parameters
        ----------
        Fy : ndarray of shape (N, k)
            The embedding F^y.
        bounds : ndarray of shape (U, 2)
            Utterance ``[start, stop)`` frame ranges (``Corpus.bounds``).
        opening : ndarray of shape (N,)
            The opening per frame: the lip aperture (:func:`engine.recordings.kinematics.lip_aperture`)
            or the quantity that stands in for it.
        rate : float
            Frames per second (velocities per second; the validation's time margin).
        source : str, default="lip aperture"
            What ``opening`` is, for ``opening_source_`` and the reports.
        unit : str, default="mm"
            Its unit ("" when it has none, as a shape component's).
        executor : object with ``map_row_blocks``, optional
            Fits blocks of frames as separate tasks (:class:`engine.scale.executor.DaskExecutor`);
            None: in-process. Same result.

        Returns
        -------
        self
        """
        Y = self._as_y(Fy, "F^y")
        self._check_params(Y.shape[1])
        N = Y.shape[0]
        d = int(self.n_dims or Y.shape[1])
        Y = np.ascontiguousarray(_finite("F^y", Y[:, :d]), dtype=np.float32)
        dim_candidates = (d,) if self.n_dims is not None else tuple(x for x in DIM_CANDIDATES if x < d) + (d,)
        b = check_bounds(bounds, N)
        op = np.asarray(opening, dtype=np.float64).reshape(-1)
        _finite("opening", op, N)
        if not (isinstance(rate, (int, float, np.floating)) and np.isfinite(rate) and rate > 0):
            raise ValueError(f"rate must be a positive number of frames per second, got {rate!r}")
        if N < 4:
            raise ValueError(f"tangent frames need at least 4 frames, got {N}")

        Z = central_difference(Y, b).astype(np.float32)
        dop = central_difference(op, b)
        F = np.column_stack([dop, central_difference(dop, b)])
        if self.n_neighbors is not None and self.n_neighbors >= N:
            raise ValueError(f"n_neighbors={self.n_neighbors} needs more than {self.n_neighbors} frames, "
                             f"got {N}; lower n_neighbors or pass None")
        if self.n_neighbors is None or len(dim_candidates) > 1:
            ks = (lambda dd: neighbor_candidates(N, dd)) if self.n_neighbors is None else (int(self.n_neighbors),)
            d, k, scores = select_neighbors(Y, Z, F, b, float(rate), candidates=ks, dims=dim_candidates,
                                            random_state=self.random_state)
            scores = np.nan_to_num(scores, nan=0.0)  # a fold with no movement scores nothing
        else:
            k, scores = int(self.n_neighbors), np.zeros((0, 4))
        Y, Z = np.ascontiguousarray(Y[:, :d]), np.ascontiguousarray(Z[:, :d])
        G, n_anchors = local_gradients(Y, Z, F, k, executor=executor, random_state=self.random_state)

        g_s, g_v = G[:, 0].astype(np.float64), G[:, 1].astype(np.float64)
        vel = np.einsum("ij,ij->i", Z, g_s) * rate
        acc = np.einsum("ij,ij->i", Z, g_v) * rate * rate
        s, ns = _unit(g_s)
        v, nv = _unit(g_v)
        bad_s, bad_v = ~(np.isfinite(ns) & (ns > 0)), ~(np.isfinite(nv) & (nv > 0))
        S = _unit(s[~bad_s].mean(axis=0))[0] if (~bad_s).any() else np.eye(d)[0]
        V = _unit(v[~bad_v].mean(axis=0))[0] if (~bad_v).any() else np.eye(d)[min(1, d - 1)]
        s[bad_s], v[bad_v] = S, V
        bad = bad_s | bad_v

        has = np.ones(N, bool)
        one = b[:, 1] - b[:, 0] == 1
        has[b[one, 0]] = False
        opening_ = (vel > 0) & has
        accel = (np.sign(acc) == np.sign(vel)) & has
        classes = (2 * (~opening_) + (~accel)).astype(np.int8)
        classes[~has] = NO_STEP

        self.n_dims_, self.n_neighbors_, self.neighbor_scores_, self.n_anchors_ = d, int(k), scores, int(n_anchors)
        self.s_, self.v_, self.step_ = s.astype(np.float32), v.astype(np.float32), Z
        self.velocity_, self.acceleration_ = vel.astype(np.float32), acc.astype(np.float32)
        self.opening_, self.accelerating_, self.classes_ = opening_, accel, classes
        self.shape_direction_, self.velocity_direction_ = S, V
        self.S_, self.plane_normal_, self.plane_point_ = self._drawn_frame(Y, S, V, np.abs(vel))
        self.n_degenerate_ = int(bad.sum())
        self.opening_source_, self.opening_unit_ = str(source), str(unit)
        self.shape_coordinate_ = op.astype(np.float32)
        return self

    def _drawn_frame(self, Y, S, V, speed):
        """(S, V, point) in Y1-3: the global directions' first three components, and the slowest frames' mean."""
        def pad(x):
            x = np.asarray(x, dtype=np.float64)[:DRAWN_DIMS]
            return np.r_[x, np.zeros(DRAWN_DIMS - len(x))]

        V3, nv = _unit(pad(V))
        if not nv > 0:
            V3 = np.eye(DRAWN_DIMS)[min(1, Y.shape[1] - 1)]
        S3 = pad(S) - (pad(S) @ V3) * V3
        S3, ns = _unit(S3)
        if not ns > 1e-9:  # S and V coincide in Y1-3: any direction orthogonal to V
            S3 = _unit(np.cross(V3, np.eye(DRAWN_DIMS)[int(np.argmin(np.abs(V3)))]))[0]
        n_low = int(min(len(Y), max(3, np.ceil(self.zero_velocity_quantile * len(Y)))))
        low = np.argpartition(speed, n_low - 1)[:n_low]
        point = pad(Y[low].astype(np.float64).mean(axis=0))
        return S3, V3, point

    # ------------------------------------------------------------------ query
    def signed_velocity(self, Y) -> np.ndarray:
        """Signed distance of points to the drawn zero-velocity plane in Y1-3 (> 0: the V side).

        A drawing aid (camera, plane): the classes and the V coordinate of a frame are
        ``velocity_``, read from its own step.

        Parameters
        ----------
        Y : ndarray of shape (n, k) or (k,)

        Returns
        -------
        ndarray of shape (n,), float64
        """
        check_is_fitted(self, "plane_normal_")
        Y = self._as_y(Y)
        Y3 = np.zeros((len(Y), DRAWN_DIMS))
        Y3[:, :min(DRAWN_DIMS, Y.shape[1])] = Y[:, :DRAWN_DIMS]
        return (Y3 - self.plane_point_) @ self.plane_normal_

    def drawn_local_frame(self, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Frame ``i``'s s_i and v_i as drawn in Y1-3 (their first three components: shorter
        than 1 by what lies in the other dims) and the unit normal of their plane there.

        Returns
        -------
        s, v, normal : ndarray of shape (3,), float64
        """
        check_is_fitted(self, "s_")
        s3, v3 = (np.r_[np.asarray(a[int(i)], np.float64)[:DRAWN_DIMS], np.zeros(max(0, DRAWN_DIMS - a.shape[1]))]
                  for a in (self.s_, self.v_))
        n3, nn = _unit(np.cross(s3, v3))
        return s3, v3, (n3 if nn > 0 else np.zeros(DRAWN_DIMS))

    def sv_coordinates(self) -> np.ndarray:
        """Per frame (S, V): the opening and its velocity read on the manifold, (N, 2) float64.

        Opening frames lie at V > 0, closing frames at V < 0 (the classes' own sign),
        and speech cycles are the paper's loops in this plane.
        """
        check_is_fitted(self, "velocity_")
        return np.column_stack([self.shape_coordinate_, self.velocity_]).astype(np.float64)

    def sv_labels(self) -> tuple[str, str]:
        """Axis labels of :meth:`sv_coordinates`, with units ("arbitrary units" when there are none)."""
        check_is_fitted(self, "velocity_")
        u = self.opening_unit_
        what = "lip aperture" if self.opening_source_ == "lip aperture" else self.opening_source_
        return ((f"S: {what} ({u})" if u else f"S: {what} (arbitrary units)"),
                (f"V: opening velocity ({u}/s)" if u else "V: opening velocity (arbitrary units/s)"))

    def sv_basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(origin (3,), S (3,), V (3,)), float64: the plane point and the global shape and velocity directions.

        S is re-orthogonalised against V (they are orthogonal by construction; this only
        guards against rounding).
        """
        check_is_fitted(self, "plane_normal_")
        V = np.asarray(self.plane_normal_, dtype=np.float64)
        V = V / np.linalg.norm(V)
        S = np.asarray(self.S_, dtype=np.float64)
        S = S - (S @ V) * V
        return np.asarray(self.plane_point_, dtype=np.float64), S / np.linalg.norm(S), V

    def class_proportions(self) -> dict:
        """Fraction of frames (with a step) in each class, ``{CLASS_NAMES[c]: fraction}``."""
        check_is_fitted(self, "classes_")
        c = np.asarray(self.classes_)
        c = c[c >= 0]
        counts = np.bincount(c, minlength=len(CLASS_NAMES)).astype(np.float64)
        frac = counts / counts.sum() if counts.sum() else counts
        return {name: float(f) for name, f in zip(CLASS_NAMES, frac)}
