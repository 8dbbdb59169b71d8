"""Phone clusters on the manifold (paper section 5).

Each phone interval of the corpus contributes its **mid-point frame**. Per phone label
the clusters hold the count (the paper's Table 1), the mean and covariance of the
members in F^y (the first ``n_dims`` dimensions of Y, with dynamics) and in F^x (the
first ``n_dims`` shape components, shape only), the 2-s.d. ellipse in any pair of axes
and the ellipsoid in 3D (Fig. 4), and the fraction of members that are opening (their
opening velocity read on the manifold, ``TangentFrames.velocity_``, is > 0).

**Separation** between two phones is the Bhattacharyya distance between Gaussian fits
of their clusters,

    D_B = 1/8 (μa − μb)ᵀ Σ⁻¹ (μa − μb) + 1/2 ln( det Σ / sqrt(det Σa det Σb) ),
    Σ = (Σa + Σb) / 2,

computed in Y and in X with the same number of dimensions. D_B is 0 for identical
clusters, grows with both the distance between the means and the difference of the
spreads, and is invariant to any invertible linear map of the space, so the Y and X
numbers are comparable although the spaces have different units. It bounds the Bayes
error of telling the two phones apart (≤ ½ exp(−D_B)). The paper's claim — dynamics
separate /m/ from /p, b/, which overlap — reads ``separation("m", "p", "y") >
separation("m", "p", "x")`` with a small ``separation("p", "b", "y")``. The simpler d'
(the mean difference over the pooled standard deviation along it) is offered as
``measure="dprime"``. A ridge of 1e-9 times the mean per-dimension variance of all
clusters keeps singular covariances (fewer members than dimensions) finite.
"""
from __future__ import annotations

from collections.abc import Sequence
from numbers import Integral
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from engine.constraints import Interval, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.phonetics import phonesets
from engine.recordings.corpus import label_codes

if TYPE_CHECKING:
    from engine.manifold.model import Manifold

__all__ = ["PhoneClusters", "bhattacharyya", "dprime", "MEASURES", "clusters_of", "LABEL_KINDS"]

#: what the clusters of :func:`clusters_of` are of
LABEL_KINDS = ("phones", "kinematic")

MEASURES = ("bhattacharyya", "dprime")
_RIDGE = 1e-9


# ------------------------------------------------------------------ Gaussian distances
def bhattacharyya(mean_a: ArrayLike, cov_a: ArrayLike, mean_b: ArrayLike, cov_b: ArrayLike) -> np.ndarray:
    """Bhattacharyya distance between Gaussians (batched over leading axes).

    Parameters
    ----------
    mean_a, mean_b : ndarray of shape (..., d)
    cov_a, cov_b : ndarray of shape (..., d, d), symmetric positive definite

    Returns
    -------
    ndarray of shape (...)
    """
    mean_a, mean_b = np.asarray(mean_a, float), np.asarray(mean_b, float)
    cov_a, cov_b = np.asarray(cov_a, float), np.asarray(cov_b, float)
    cov = 0.5 * (cov_a + cov_b)
    diff = mean_a - mean_b
    maha = np.einsum("...i,...i->...", diff, np.linalg.solve(cov, diff[..., None])[..., 0])
    _, ld = np.linalg.slogdet(cov)
    _, lda = np.linalg.slogdet(cov_a)
    _, ldb = np.linalg.slogdet(cov_b)
    return maha / 8.0 + 0.5 * (ld - 0.5 * (lda + ldb))


def dprime(mean_a: ArrayLike, cov_a: ArrayLike, mean_b: ArrayLike, cov_b: ArrayLike) -> np.ndarray:
    """d' along the mean difference: ``|μa − μb| / sqrt(½ (wᵀΣa w + wᵀΣb w))``, w the unit difference.

    Shapes as :func:`bhattacharyya`; 0 where the means coincide.
    """
    diff = np.asarray(mean_a, float) - np.asarray(mean_b, float)
    norm = np.linalg.norm(diff, axis=-1)
    w = diff / np.where(norm > 0, norm, 1.0)[..., None]
    var = 0.5 * (np.einsum("...i,...ij,...j->...", w, np.asarray(cov_a, float), w)
                 + np.einsum("...i,...ij,...j->...", w, np.asarray(cov_b, float), w))
    return np.where(norm > 0, norm / np.sqrt(np.maximum(var, np.finfo(float).tiny)), 0.0)


def _whitener(cov: np.ndarray) -> np.ndarray:
    """L with L Lᵀ = cov and det L ≥ 0 (so meshes keep their orientation)."""
    lam, V = np.linalg.eigh(cov)
    if np.linalg.det(V) < 0:
        V = V.copy()
        V[:, 0] = -V[:, 0]
    return V * np.sqrt(np.clip(lam, 0.0, None))


def _sphere(resolution: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit UV sphere: vertices (n, 3), outward-oriented triangles (m, 3)."""
    n_lon, n_lat = max(int(resolution), 3), max(int(resolution) // 2, 2)
    phi = np.linspace(0.0, np.pi, n_lat + 1)[1:-1]
    theta = np.linspace(0.0, 2 * np.pi, n_lon, endpoint=False)
    sp, cp = np.sin(phi)[:, None], np.cos(phi)[:, None]
    ring = np.stack([sp * np.cos(theta), sp * np.sin(theta), np.broadcast_to(cp, (phi.size, n_lon))], axis=-1)
    verts = np.vstack([[0.0, 0.0, 1.0], ring.reshape(-1, 3), [0.0, 0.0, -1.0]])
    south = verts.shape[0] - 1
    j = np.arange(n_lon)
    jn = (j + 1) % n_lon
    faces = [np.column_stack([np.zeros(n_lon, int), 1 + j, 1 + jn])]
    for r in range(phi.size - 1):
        a, b = 1 + r * n_lon + j, 1 + r * n_lon + jn
        c, d = a + n_lon, b + n_lon
        faces += [np.column_stack([a, c, d]), np.column_stack([a, d, b])]
    last = 1 + (phi.size - 1) * n_lon
    faces.append(np.column_stack([np.full(n_lon, south), last + jn, last + j]))
    return verts, np.vstack(faces).astype(np.int64)


# ------------------------------------------------------------------ the estimator
class PhoneClusters(Estimator):
    """Per-phone statistics of phone mid-point frames in F^y and F^x.

    Parameters
    ----------
    n_dims : int, default=3
        Dimensions of Y (and shape components of X) the statistics use.
    min_count : int, default=3
        Phones with fewer mid-points are left out (listed in ``excluded_phones_``).
    exclude_pauses : bool, default=True
        Leave out pause labels (sil, sp, pau, #, blank, ...; see :mod:`engine.phonetics.phonesets`).
    normalize_labels : bool, default=False
        Merge labels through :func:`engine.phonetics.phonesets.normalize` (``AH0``/``ax`` -> ``ax``),
        in the phone set :func:`engine.phonetics.phonesets.detect_phoneset` finds; labels no set
        knows are kept as given. False keeps the corpus's own labels.

    Attributes
    ----------
    phones_ : list of str
        Phones with at least ``min_count`` members, by count (descending), then label.
    counts_ : ndarray of shape (P,), int64
    means_ : ndarray of shape (P, d), float64
        Means in F^y (first ``n_dims_`` dimensions).
    covariances_ : ndarray of shape (P, d, d), float64
        Sample covariances (ddof=1) in F^y.
    means_x_ : ndarray of shape (P, dx), float64
        Means in F^x (first ``n_dims_x_`` = min(n_dims, m) shape components).
    covariances_x_ : ndarray of shape (P, dx, dx), float64
    opening_fraction_ : ndarray of shape (P,), float64
        Fraction of members whose opening velocity is > 0 (opening); NaN when no
        velocity was given.
    members_ : ndarray of shape (M,), int64
        Mid-point frame indices, phone after phone (``members_[member_offsets_[p]:member_offsets_[p+1]]``).
    member_offsets_ : ndarray of shape (P + 1,), int64
    member_velocity_ : ndarray of shape (M,), float64 or None
        Signed velocity of each member.
    n_dims_, n_dims_x_ : int
    phoneset_ : str
        Phone set detected from the labels (used for classes and normalisation).
    excluded_phones_ : list of str
        Labels with fewer than ``min_count`` members (pauses are not listed).
    excluded_counts_ : ndarray of shape (len(``excluded_phones_``),), int64
    n_pauses_ : int
        Pause instances left out.
    """

    _parameter_constraints = {
        "n_dims": [Interval(Integral, 1, None, closed="left")],
        "min_count": [Interval(Integral, 2, None, closed="left")],  # a covariance needs two members
        "exclude_pauses": ["boolean"],
        "normalize_labels": ["boolean"],
    }

    def __init__(self, *, n_dims: int = 3, min_count: int = 3, exclude_pauses: bool = True,
                 normalize_labels: bool = False) -> None:
        self.n_dims = n_dims
        self.min_count = min_count
        self.exclude_pauses = exclude_pauses
        self.normalize_labels = normalize_labels

    # ------------------------------------------------------------------ fitting
    @classmethod
    def from_manifold(cls, manifold: Manifold, **params: Any) -> PhoneClusters:
        """Fit on a fitted :class:`engine.manifold.model.Manifold` (its corpus's phone table,
        ``Fy_``, ``Fx_`` and the tangent frames' opening velocity per frame)."""
        return cls(**params).fit(manifold)

    def fit(self, Fy: Any, Fx: Any = None, mid_frames: Any = None, labels: Any = None,
            signed_velocity: Any = None) -> PhoneClusters:
        """Fit from a manifold, ``fit(manifold)``, or from arrays.

        Parameters
        ----------
        Fy : ndarray of shape (N, k >= n_dims), or a fitted Manifold
        Fx : ndarray of shape (N, m)
        mid_frames : int array of shape (n_phones,)
            Mid-point frame of each phone instance, in [0, N).
        labels : sequence of str of length n_phones
        signed_velocity : None, ndarray of shape (N,), or callable
            The opening velocity per frame (> 0 opening; ``manifold.tangent_.velocity_``),
            or a function of F^y rows returning it.

        Returns
        -------
        self
        """
        validate_params(self)
        if Fx is None and mid_frames is None and labels is None and hasattr(Fy, "Fy_") and hasattr(Fy, "corpus_"):
            m = Fy
            mids, labs = m.corpus_.phone_table()[:2]
            tangent = getattr(m, "tangent_", None)
            sv = None if tangent is None else tangent.velocity_
            return self.fit(m.Fy_, m.Fx_, mids, labs, signed_velocity=sv)
        if Fx is None or mid_frames is None or labels is None:
            raise TypeError("fit(manifold) or fit(Fy, Fx, mid_frames, labels, signed_velocity=None): "
                            "give a fitted Manifold alone, or all four arrays")
        Fy, Fx, mids, labels, sv = self._check_inputs(Fy, Fx, mid_frames, labels, signed_velocity)
        d, dx = self.n_dims, min(self.n_dims, Fx.shape[1])

        phoneset = phonesets.detect_phoneset(labels)
        keep = np.ones(len(labels), bool)
        # each distinct label is looked up once (a million-frame corpus has ~10^5 phones of ~50 labels)
        distinct, which = label_codes(labels)
        if self.exclude_pauses:
            keep = ~np.array([phonesets.is_pause(x, phoneset=phoneset) for x in distinct], bool)[which]
        if self.normalize_labels:
            norm = [phonesets.normalize(x, strict=False, phoneset=phoneset) for x in distinct]
            mapped = np.array([x if n == phonesets.UNKNOWN else n for x, n in zip(distinct, norm)], dtype=object)
            labels = list(mapped[which])
        labels = np.asarray(labels, dtype=object)[keep]
        mids = mids[keep]

        names, inverse = label_codes(labels.astype(str))
        counts = np.bincount(inverse, minlength=names.size)
        order = sorted(range(names.size), key=lambda i: (-counts[i], names[i]))
        kept = [i for i in order if counts[i] >= self.min_count]
        dropped = [i for i in order if counts[i] < self.min_count]

        members, offsets = [], [0]
        means, covs, means_x, covs_x = [], [], [], []
        for i in kept:
            idx = mids[inverse == i]
            members.append(idx)
            offsets.append(offsets[-1] + idx.size)
            Y = Fy[idx, :d].astype(np.float64)
            X = Fx[idx, :dx].astype(np.float64)
            means.append(Y.mean(axis=0))
            covs.append(np.atleast_2d(np.cov(Y, rowvar=False)))
            means_x.append(X.mean(axis=0))
            covs_x.append(np.atleast_2d(np.cov(X, rowvar=False)))
        P = len(kept)
        self.phones_ = [str(names[i]) for i in kept]
        self.counts_ = np.array([counts[i] for i in kept], dtype=np.int64)
        self.means_ = np.array(means, dtype=np.float64).reshape(P, d)
        self.covariances_ = np.array(covs, dtype=np.float64).reshape(P, d, d)
        self.means_x_ = np.array(means_x, dtype=np.float64).reshape(P, dx)
        self.covariances_x_ = np.array(covs_x, dtype=np.float64).reshape(P, dx, dx)
        self.members_ = np.concatenate(members).astype(np.int64) if members else np.zeros(0, np.int64)
        self.member_offsets_ = np.array(offsets, dtype=np.int64)
        if sv is None:
            self.member_velocity_ = None
            self.opening_fraction_ = np.full(P, np.nan)
        else:
            v = np.asarray(sv(Fy[self.members_]) if callable(sv) else sv[self.members_], dtype=np.float64).ravel()
            if v.shape != self.members_.shape or not np.all(np.isfinite(v)):
                raise ValueError(f"signed_velocity gave {v.shape} values (finite: {np.isfinite(v).all()}) for "
                                 f"{self.members_.size} members; it must return one finite value per F^y row")
            self.member_velocity_ = v
            opening = np.add.reduceat((v > 0).astype(np.int64), offsets[:-1]) if P else np.zeros(0, np.int64)
            self.opening_fraction_ = opening.astype(np.float64) / np.maximum(self.counts_, 1)
        self.n_dims_, self.n_dims_x_ = int(d), int(dx)
        self.phoneset_ = phoneset
        self.excluded_phones_ = [str(names[i]) for i in dropped]
        self.excluded_counts_ = np.array([counts[i] for i in dropped], dtype=np.int64)
        self.n_pauses_ = int((~keep).sum())
        return self

    def _check_inputs(self, Fy: Any, Fx: Any, mid_frames: Any, labels: Any, sv: Any) -> tuple[Any, ...]:
        Fy, Fx = np.asarray(Fy), np.asarray(Fx)
        for name, a in (("Fy", Fy), ("Fx", Fx)):
            if a.ndim != 2 or not np.issubdtype(a.dtype, np.number):
                raise ValueError(f"{name} must be a 2-D numeric array (frames x dims), got shape {a.shape} {a.dtype}")
        N = Fy.shape[0]
        if Fy.shape[1] < self.n_dims:
            raise ValueError(f"n_dims={self.n_dims} but F^y has {Fy.shape[1]} dimensions; lower n_dims to "
                             f"<= {Fy.shape[1]} or build the manifold with more embedding dimensions")
        if Fx.shape[0] != N:
            raise ValueError(f"Fx has {Fx.shape[0]} frames but Fy has {N}; pass both for the same frames")
        mids = np.asarray(mid_frames)
        if mids.ndim != 1 or (mids.size and not np.issubdtype(mids.dtype, np.integer)):
            raise ValueError(f"mid_frames must be a 1-D integer array, got shape {mids.shape} {mids.dtype}")
        mids = mids.astype(np.int64)
        labels = labels.tolist() if isinstance(labels, np.ndarray) and labels.dtype.kind == "U" else \
            [str(x) for x in labels]
        if len(labels) != mids.size:
            raise ValueError(f"{len(labels)} labels for {mids.size} mid_frames; give one label per phone instance")
        bad = np.flatnonzero((mids < 0) | (mids >= N))
        if bad.size:
            raise ValueError(f"mid_frames[{bad[0]}] = {mids[bad[0]]} ({labels[bad[0]]!r}) is outside the "
                             f"{N} frames [0, {N}); mid-points must index rows of Fy")
        used = np.unique(mids)
        for name, a in (("Fy", Fy), ("Fx", Fx)):
            rows = np.flatnonzero(~np.isfinite(a[used]).all(axis=1))
            if rows.size:
                raise ValueError(f"{name} row {used[rows[0]]} (a phone mid-point) is not finite")
        if sv is not None and not callable(sv):
            sv = np.asarray(sv, dtype=np.float64).ravel()
            if sv.shape != (N,):
                raise ValueError(f"signed_velocity has shape {sv.shape}; expected ({N},), one value per frame, "
                                 "or a callable on F^y rows")
        return Fy, Fx, mids, labels, sv

    # ------------------------------------------------------------------ lookup
    def index(self, phone: str) -> int:
        """Row of ``phone`` in ``phones_`` (exact label first, then by phone-set normalisation)."""
        check_is_fitted(self, "phones_")
        if phone in self.phones_:
            return self.phones_.index(phone)
        key = phonesets.normalize(str(phone), strict=False)
        if key != phonesets.UNKNOWN:
            hits = [i for i, p in enumerate(self.phones_)
                    if phonesets.normalize(p, strict=False, phoneset=self.phoneset_) == key]
            if len(hits) == 1:
                return hits[0]
        why = ""
        if phone in self.excluded_phones_:
            n = int(self.excluded_counts_[self.excluded_phones_.index(phone)])
            why = f" (it has {n} mid-points, fewer than min_count={self.min_count})"
        raise ValueError(f"no cluster for phone {phone!r}{why}; phones with clusters: {' '.join(self.phones_)}")

    def members(self, phone: str) -> np.ndarray:
        """Mid-point frame indices of ``phone``, shape (count,)."""
        i = self.index(phone)
        return self.members_[self.member_offsets_[i]:self.member_offsets_[i + 1]]

    def _space(self, space: str) -> tuple[np.ndarray, np.ndarray]:
        s = str(space).lower()
        if s == "y":
            return self.means_, self.covariances_
        if s == "x":
            return self.means_x_, self.covariances_x_
        raise ValueError(f"space={space!r}: use 'y' (F^y, with dynamics) or 'x' (F^x, shape only)")

    def _axes(self, axes: Sequence[int], n: int, dim: int) -> list[int]:
        axes = tuple(int(a) for a in axes)
        if len(axes) != n or len(set(axes)) != n or min(axes) < 0 or max(axes) >= dim:
            raise ValueError(f"axes={axes}: need {n} distinct axes in [0, {dim}); fit with a larger n_dims "
                             "for higher axes")
        return list(axes)

    # ------------------------------------------------------------------ geometry
    def ellipse(self, phone: str, axes: Sequence[int] = (0, 1), n_sd: float = 2.0, n_points: int = 100, *,
                space: str = "y") -> np.ndarray:
        """Outline of the ``n_sd``-s.d. ellipse of ``phone`` in the plane of two axes.

        The ellipse of the cluster's marginal Gaussian in those axes: every point has
        Mahalanobis distance ``n_sd`` from the mean. Points go once round, without
        repeating the first (append it to draw a closed line).

        Returns
        -------
        ndarray of shape (n_points, 2)
        """
        check_is_fitted(self, "phones_")
        means, covs = self._space(space)
        i, ax = self.index(phone), self._axes(axes, 2, means.shape[1])
        t = np.linspace(0.0, 2 * np.pi, int(n_points), endpoint=False)
        L = _whitener(covs[i][np.ix_(ax, ax)])
        return means[i, ax] + float(n_sd) * np.column_stack([np.cos(t), np.sin(t)]) @ L.T

    def ellipsoid(self, phone: str, n_sd: float = 2.0, resolution: int = 20, *, axes: Sequence[int] = (0, 1, 2),
                  space: str = "y") -> tuple[np.ndarray, np.ndarray]:
        """Triangle mesh of the ``n_sd``-s.d. ellipsoid of ``phone`` in three axes.

        Every vertex has Mahalanobis distance ``n_sd`` from the mean; triangles are
        oriented outward. ``resolution`` segments round, ``resolution // 2`` from pole to pole.

        Returns
        -------
        vertices : ndarray of shape (n, 3), float64
        faces : ndarray of shape (m, 3), int64
        """
        check_is_fitted(self, "phones_")
        means, covs = self._space(space)
        i, ax = self.index(phone), self._axes(axes, 3, means.shape[1])
        unit, faces = _sphere(resolution)
        L = _whitener(covs[i][np.ix_(ax, ax)])
        return means[i, ax] + float(n_sd) * unit @ L.T, faces

    # ------------------------------------------------------------------ separation
    def _regularised(self, covs: np.ndarray) -> np.ndarray:
        d = covs.shape[-1]
        scale = float(np.mean(np.trace(covs, axis1=1, axis2=2))) / d if covs.size else 1.0
        return covs + _RIDGE * (scale if scale > 0 else 1.0) * np.eye(d)

    def separation(self, a: str, b: str, space: str = "y", *, measure: str = "bhattacharyya") -> float:
        """Separation of the clusters of phones ``a`` and ``b`` in Y (``"y"``) or X (``"x"``).

        ``measure="bhattacharyya"`` (default, see the module docstring) or ``"dprime"``.
        """
        i, j = self.index(a), self.index(b)
        return float(self.separation_matrix(space, measure=measure, phones=[self.phones_[i], self.phones_[j]])[0, 1])

    def separation_matrix(self, space: str = "y", *, measure: str = "bhattacharyya",
                          phones: Sequence[str] | None = None) -> np.ndarray:
        """Pairwise separations, shape (P, P) in ``phones_`` order (or of ``phones``); zero diagonal."""
        check_is_fitted(self, "phones_")
        if measure not in MEASURES:
            raise ValueError(f"measure={measure!r}: use one of {', '.join(MEASURES)}")
        means, covs = self._space(space)
        covs = self._regularised(covs)
        idx = np.arange(len(self.phones_)) if phones is None else np.array([self.index(p) for p in phones], int)
        mu, C = means[idx], covs[idx]
        fn = bhattacharyya if measure == "bhattacharyya" else dprime
        out = fn(mu[:, None], C[:, None], mu[None], C[None])
        np.fill_diagonal(out, 0.0)
        return np.maximum(out, 0.0)

    # ------------------------------------------------------------------ table
    def table(self, phones: Sequence[str] | None = None, *, measure: str = "bhattacharyya") -> list[dict[str, Any]]:
        """One row per phone (all of ``phones_``, or ``phones``), for printing and CSV.

        Keys: ``phone``, ``count``, ``y1..yd`` (mean in F^y), ``opening_fraction``,
        ``broad_class``, ``lipreading_class``, ``nearest_y`` (the phone with the smallest
        separation in Y, among all clusters), ``separation_y`` and ``separation_x``
        (separation from ``nearest_y`` in Y and in X), ``nearest_x`` and
        ``separation_nearest_x`` (the nearest phone in X and that separation).
        Separations use ``measure``; with a single cluster they are NaN and the
        nearest phones None.
        """
        check_is_fitted(self, "phones_")
        rows_of = range(len(self.phones_)) if phones is None else [self.index(p) for p in phones]
        Sy, Sx = self.separation_matrix("y", measure=measure), self.separation_matrix("x", measure=measure)
        P = len(self.phones_)
        rows = []
        for i in rows_of:
            ph = self.phones_[i]
            row = {"phone": ph, "count": int(self.counts_[i])}
            row.update({f"y{k + 1}": float(v) for k, v in enumerate(self.means_[i])})
            row["opening_fraction"] = float(self.opening_fraction_[i])
            row["broad_class"] = phonesets.broad_class(ph, strict=False, phoneset=self.phoneset_)
            row["lipreading_class"] = phonesets.lipreading_class(ph, strict=False, phoneset=self.phoneset_)
            if P > 1:
                oy = np.where(np.arange(P) == i, np.inf, Sy[i])
                ox = np.where(np.arange(P) == i, np.inf, Sx[i])
                ny, nx = int(np.argmin(oy)), int(np.argmin(ox))
                row.update(nearest_y=self.phones_[ny], separation_y=float(Sy[i, ny]), separation_x=float(Sx[i, ny]),
                           nearest_x=self.phones_[nx], separation_nearest_x=float(Sx[i, nx]))
            else:
                row.update(nearest_y=None, separation_y=np.nan, separation_x=np.nan, nearest_x=None,
                           separation_nearest_x=np.nan)
            rows.append(row)
        return rows


def clusters_of(manifold: Manifold, *, labels: str = "auto",
                **params: Any) -> tuple[PhoneClusters, str, str | None]:
    """Clusters of a fitted manifold's phone mid-points, or of its kinematic landmarks when it has no phones.

    Parameters
    ----------
    manifold : engine.manifold.model.Manifold
    labels : {"auto", "phones", "kinematic"}
        ``auto``: phones when the corpus has any, else the kinematic landmarks of the lip
        aperture (:func:`engine.recordings.kinematics.kinematic_if_unlabelled`: aperture maxima
        ``open``, minima ``closed``, peak velocities ``opening`` / ``closing``); a corpus
        already labelled with landmarks counts as landmarks.
    **params
        :class:`PhoneClusters` parameters.

    Returns
    -------
    clusters : PhoneClusters
        Fitted; its labels are the phones or the landmark names.
    kind : {"phones", "kinematic"}
    note : str or None
        For landmarks, the sentence saying so (None for phones).

    Raises
    ------
    ValueError
        ``labels="phones"`` for a corpus without phone labels (naming the fix).
    """
    from dataclasses import replace

    from engine.recordings.kinematics import has_kinematic_labels, kinematic_if_unlabelled

    if labels not in ("auto", *LABEL_KINDS):
        raise ValueError(f"labels={labels!r}; expected 'auto', 'phones' or 'kinematic'")
    c = manifold.corpus_
    has_phones = any(u.phones for u in c.utterances)
    landmarks = has_kinematic_labels(c)
    kind = labels if labels != "auto" else ("kinematic" if landmarks or not has_phones else "phones")
    if kind == "phones" and (landmarks or not has_phones):
        raise ValueError(f"{c.name} has no phone labels; cluster its kinematic landmarks (lipspace clusters "
                         "--labels kinematic), or import it with an alignment (lipspace import --alignment)")
    pc = PhoneClusters(**params)
    if kind == "phones" or landmarks:
        return pc.fit(manifold), kind, (None if kind == "phones" else
                                        f"{c.name}: labels are kinematic landmarks (open, closed, opening, closing)")
    kc, note = kinematic_if_unlabelled(replace(c, utterances=[replace(u, phones=()) for u in c.utterances]))
    mids, labs = kc.phone_table()[:2]
    tangent = getattr(manifold, "tangent_", None)
    pc.fit(manifold.Fy_, manifold.Fx_, mids, labs, signed_velocity=None if tangent is None else tangent.velocity_)
    return pc, kind, note
