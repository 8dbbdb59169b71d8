"""Held-out synthesis evaluation, per method (the older table; ``lipspace evaluate --methods``).

The methods of this table do not get the same information (the manifold gets the
target's state, which carries shape *and* velocity, the interpolations only its X) and
the manifold is scored in Y on its state centroids while the others are projected; it
cannot decide whether the manifold path beats direct interpolation. The evaluation of
record is :mod:`engine.evaluation.protocols` (equal information, one projection for all, LVE, paired
statistics), whose results are in docs/RESULTS.md.

Whole utterances are held out; the manifold is fitted on the rest. Each held-out
utterance is resynthesised from its phone sequence and compared with its own frames.

Methods (names accepted by :func:`evaluate`)
    ``manifold``         oracle targets: the held-out phone mid-point frames projected
                         out-of-sample (shape -> dynamics -> embedding) to their states.
    ``linear``, ``cubic`` direct interpolation of the same mid-point frames' F^x.
    ``manifold-phones``  phone labels and times only: target states chosen from the
                         phones' clusters (lattice Viterbi).
    ``linear-phones``, ``cubic-phones``  interpolation of the phones' mean F^x.
    ``unitselection``    concatenative unit selection from phone labels and times.

Measures, over the frames from the first to the last target of every held-out
utterance (outside that span every method merely holds a target):

* ``rmse_x`` -- root mean square over frames of the Euclidean error in X (shape
  space, the corpus's units since the PCA basis is orthonormal);
* ``mean_point_error``, ``max_point_error`` -- Euclidean distance per point between
  the reconstructed frame and the real frame, in the corpus's units, averaged over
  points and frames / largest;
* ``corr_1..3`` -- Pearson correlation of the first three X components, synthetic
  against real, over all compared frames;
* ``rmse_y`` -- root mean square over frames of the Euclidean error in the first three
  dimensions of Y, the manifold the paper draws (its Fig. 3, where it claims the
  manifold path beats direct interpolation of the phone targets). The truth is the
  held-out utterance's own out-of-sample F^y (:meth:`Manifold.project`). A method that
  moves in Y (``manifold``, ``manifold-phones``) is scored on its state-centroid path,
  *before* the inverse map; a method that moves in X (interpolation, unit selection) has
  its whole synthetic X trajectory projected out-of-sample through the same fitted
  pipeline (velocities inside the utterance -> dynamic features -> embedding), see
  :func:`project_x`. Units are those of Y (scaled dynamic features), not the corpus's.

Only utterances every requested method could synthesise are scored (so the rows
compare like with like); failures are counted per method.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from engine.manifold.model import project_x
from engine.progress import ProgressFn, report

__all__ = ["evaluate", "EvaluationResult", "EVALUATION_METHODS", "DEFAULT_METHODS", "split_utterances",
           "trajectory_errors", "project_x", "trajectory_y"]

EVALUATION_METHODS = ("manifold", "linear", "cubic", "unitselection", "manifold-phones", "linear-phones",
                      "cubic-phones")
DEFAULT_METHODS = ("manifold", "linear", "cubic", "unitselection")
_COLUMNS = ("method", "utterances", "frames", "rmse_x", "mean_point_error", "max_point_error",
            "corr_1", "corr_2", "corr_3", "rmse_y", "failures", "missed_targets")
#: dimensions of Y scored by ``rmse_y``: the 3-D manifold of the paper's figures
Y_DIMS = 3


@dataclass
class EvaluationResult:
    """Per-method error table of a held-out evaluation.

    Attributes
    ----------
    rows : list of dict
        One per method, keys :data:`_COLUMNS`.
    test_ids, train_ids : list of str
    n_train_frames : int
    per_utterance : list of dict
        ``{"utterance", "method", "frames", "rmse_x", "mean_point_error", "rmse_y"}`` per scored pair.
    failures : dict of str to list of str
        Method -> messages of the utterances it could not synthesise.
    corpus : str
    """

    rows: list
    test_ids: list
    train_ids: list
    n_train_frames: int
    per_utterance: list = field(default_factory=list)
    failures: dict = field(default_factory=dict)
    corpus: str = ""

    def table(self) -> list[dict]:
        """The rows (one dict per method)."""
        return [dict(r) for r in self.rows]

    def row(self, method: str) -> dict:
        for r in self.rows:
            if r["method"] == method:
                return dict(r)
        raise KeyError(f"no method {method!r} in this evaluation; it has {[r['method'] for r in self.rows]}")

    def format(self) -> str:
        """The table as aligned text."""
        head = ["method", "utts", "frames", "RMSE X", "mean pt err", "max pt err", "r1", "r2", "r3", "RMSE Y3",
                "failed", "missed"]
        lines = []
        for r in self.rows:
            lines.append([r["method"], str(r["utterances"]), str(r["frames"]), _f(r["rmse_x"]),
                          _f(r["mean_point_error"]), _f(r["max_point_error"]), _f(r["corr_1"], 3),
                          _f(r["corr_2"], 3), _f(r["corr_3"], 3), _f(r["rmse_y"]), str(r["failures"]),
                          str(r["missed_targets"])])
        w = [max(len(h), *(len(x[i]) for x in lines)) if lines else len(h) for i, h in enumerate(head)]
        fmt = lambda row: "  ".join(s.rjust(w[i]) if i else s.ljust(w[i]) for i, s in enumerate(row))  # noqa: E731
        out = [f"held-out synthesis on {self.corpus}: {len(self.test_ids)} test utterance(s), "
               f"{len(self.train_ids)} training ({self.n_train_frames} frames); errors in corpus units, "
               f"except RMSE Y3: first {Y_DIMS} dims of the manifold Y (its own units)",
               fmt(head), fmt(["-" * x for x in w])]
        out += [fmt(x) for x in lines]
        for m, msgs in self.failures.items():
            if msgs:
                out.append(f"{m}: {len(msgs)} failure(s), e.g. {msgs[0]}")
        return "\n".join(out)


def _error_arrays(manifold, Fx_hat, frames, dims):
    """Per-frame Euclidean error in X (n,) and per-point error in the corpus's units (n, V)."""
    Fx_hat = np.asarray(Fx_hat)
    frames = np.asarray(frames)
    X_true = manifold.shape_.transform(frames).astype(np.float64)
    err_x = np.linalg.norm(Fx_hat.astype(np.float64) - X_true, axis=1)
    n = frames.shape[0]
    F_hat = manifold.shape_.inverse_transform(Fx_hat).astype(np.float64).reshape(n, -1, dims)
    err_p = np.linalg.norm(F_hat - frames.astype(np.float64).reshape(n, -1, dims), axis=2)
    return err_x, err_p, X_true


def trajectory_errors(manifold, Fx_hat, frames) -> dict:
    """Errors of a synthetic trajectory against the real frames it stands for.

    Parameters
    ----------
    manifold : Manifold
        Fitted; its shape space defines X.
    Fx_hat : ndarray of shape (n, m)
        Synthetic shape coordinates.
    frames : ndarray of shape (n, C)
        The real frames.

    Returns
    -------
    dict
        ``rmse_x`` (root mean square over frames of the Euclidean error in X),
        ``mean_point_error`` and ``max_point_error`` (Euclidean per point, corpus units),
        ``frames``.
    """
    dims = manifold.corpus_.dims
    err_x, err_p, _ = _error_arrays(manifold, Fx_hat, frames, dims)
    return {"rmse_x": float(np.sqrt((err_x ** 2).mean())), "mean_point_error": float(err_p.mean()),
            "max_point_error": float(err_p.max()), "frames": int(err_x.size)}


def trajectory_y(manifold, trajectory, dims=Y_DIMS) -> np.ndarray:
    """A synthetic trajectory in the first ``dims`` dimensions of Y, frame by frame.

    A trajectory that moves in Y (the manifold method) is its own path: the state
    centroids, before any inverse map (if the states were clustered in fewer than
    ``dims`` dimensions, each state's mean F^y over its members stands in). Any other
    (it moves in X) is projected out-of-sample with :func:`project_x`.

    Returns
    -------
    ndarray of shape (n, dims), float64
    """
    dims = min(int(dims), manifold.Fy_.shape[1])
    if trajectory.Fy is not None and trajectory.Fy.shape[1] >= dims:
        return np.asarray(trajectory.Fy[:, :dims], dtype=np.float64)
    if trajectory.Fy is not None and trajectory.states is not None:
        lab = np.asarray(manifold.states_.labels_)
        K = int(manifold.states_.centroids_.shape[0])
        n = np.maximum(np.bincount(lab, minlength=K), 1)
        Fy = np.asarray(manifold.Fy_[:, :dims], dtype=np.float64)
        means = np.stack([np.bincount(lab, weights=Fy[:, j], minlength=K) for j in range(dims)], 1) / n[:, None]
        return means[np.asarray(trajectory.states)]
    return project_x(manifold, trajectory.Fx)[:, :dims].astype(np.float64)


def _f(v, nd=4):
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return "nan"
    return f"{v:.{nd}g}"


def split_utterances(corpus, *, test_fraction=0.1, test_ids=None, random_state=0):
    """(train ids, test ids): ``test_ids`` as given, else a seeded random ``test_fraction`` (at least one)."""
    ids = [u.id for u in corpus.utterances]
    if len(ids) < 2:
        raise ValueError(f"{corpus.name} has {len(ids)} utterance(s); holding out whole utterances needs at least 2")
    if test_ids is not None:
        test = [str(t) for t in test_ids]
        unknown = [t for t in test if t not in ids]
        if unknown:
            raise ValueError(f"test utterance(s) {unknown[:5]} not in {corpus.name}; it has {ids[:8]}...")
        if len(set(test)) >= len(ids):
            raise ValueError("every utterance is a test utterance; leave at least one for training")
    else:
        if not 0 < float(test_fraction) < 1:
            raise ValueError(f"test_fraction must be in (0, 1), got {test_fraction}")
        k = min(len(ids) - 1, max(1, int(round(float(test_fraction) * len(ids)))))
        rng = np.random.default_rng(random_state)
        test = sorted(rng.choice(len(ids), size=k, replace=False).tolist())
        test = [ids[i] for i in test]
    ts = set(test)
    return [i for i in ids if i not in ts], test


def fit_on_training_split(corpus, *, test_fraction=0.1, test_ids=None, random_state=0, manifold_factory=None,
                          progress=None):
    """Split ``corpus`` by whole utterances and fit a manifold on the training part only.

    Returns
    -------
    train_ids, test_ids : list of str
    train : Corpus
        The training utterances.
    manifold : Manifold
        ``manifold_factory(train)``, or ``Manifold(random_state=random_state)`` fitted on ``train``.
    """
    train_ids, test = split_utterances(corpus, test_fraction=test_fraction, test_ids=test_ids,
                                       random_state=random_state)
    train = corpus.subset(train_ids)
    if manifold_factory is None:
        from engine.manifold.model import Manifold

        manifold = Manifold(random_state=random_state).fit(train, progress=progress)
    else:
        manifold = manifold_factory(train)
    return train_ids, test, train, manifold


def _synthesizers(manifold, methods, params):
    from engine.synthesis.unitselection import UnitSelectionSynthesizer
    from engine.synthesis.viterbi import InterpolationSynthesizer, ManifoldSynthesizer

    out = {}
    for m in methods:
        base = m.replace("-phones", "")
        p = dict(params.get(m, params.get(base, {})))
        if base == "manifold":
            p.setdefault("strict", False)
            out[m] = ManifoldSynthesizer(**p).fit(manifold)
        elif base in ("linear", "cubic"):
            out[m] = InterpolationSynthesizer(kind=base, **p).fit(manifold)
        else:
            out[m] = UnitSelectionSynthesizer(**p).fit(manifold)
    return out


def evaluate(corpus, *, manifold_factory=None, test_fraction=0.1, test_ids=None, methods=DEFAULT_METHODS,
             random_state=0, synthesizer_params=None, progress: ProgressFn = None) -> EvaluationResult:
    """Hold out whole utterances, fit on the rest, resynthesise the held-out ones with every method.

    Parameters
    ----------
    corpus : Corpus
        Phone-aligned corpus.
    manifold_factory : callable, optional
        ``manifold_factory(train_corpus) -> fitted Manifold``; default
        ``Manifold(random_state=random_state).fit(train_corpus)``.
    test_fraction : float, default=0.1
        Fraction of utterances held out (at least one), ignored with ``test_ids``.
    test_ids : sequence of str, optional
        Utterances to hold out.
    methods : sequence of str
        From :data:`EVALUATION_METHODS`.
    random_state : int
        Seeds the split and the default manifold.
    synthesizer_params : dict, optional
        Method (or base method, e.g. "manifold") -> constructor parameters.
    progress : callable, optional

    Returns
    -------
    EvaluationResult
    """
    from engine.phonetics.targets import TargetError, targets_from_utterance

    methods = list(methods)
    bad = [m for m in methods if m not in EVALUATION_METHODS]
    if bad or not methods:
        raise ValueError(f"unknown evaluation method(s) {bad}; choose from {', '.join(EVALUATION_METHODS)}")
    train_ids, test, train, manifold = fit_on_training_split(
        corpus, test_fraction=test_fraction, test_ids=test_ids, random_state=random_state,
        manifold_factory=manifold_factory, progress=progress)
    synths = _synthesizers(manifold, methods, synthesizer_params or {})
    dims = corpus.dims
    acc = {m: {"sq": 0.0, "sq_y": 0.0, "n": 0, "pt_sum": 0.0, "pt_n": 0, "pt_max": 0.0, "hat": [], "true": [], "utts": 0,
               "missed": 0} for m in methods}
    failures = {m: [] for m in methods}
    per_utt = []
    for k, uid in enumerate(test):
        report(progress, "evaluation", k, len(test))
        u = corpus.utterance(uid)
        F = corpus.frames[u.start:u.stop]
        try:
            tg = targets_from_utterance(manifold, uid, corpus=corpus, on_collision="merge")
        except (TargetError, ValueError) as exc:
            for m in methods:
                failures[m].append(f"{uid}: {exc}")
            continue
        lo, hi = int(tg.frames[0]), int(tg.frames[-1]) + 1
        results = {}
        for m in methods:
            t_in = tg.phones_only() if (m.endswith("-phones") or m == "unitselection") else tg
            try:
                results[m] = synths[m].synthesize(t_in)
            except ValueError as exc:
                failures[m].append(f"{uid}: {exc}")
        if len(results) < len(methods):
            continue  # score only utterances every method could synthesise
        Y_true = manifold.project(F)[lo:hi, :Y_DIMS].astype(np.float64)
        for m, tr in results.items():
            Xh = tr.Fx[lo:hi].astype(np.float64)
            err, pe, X_true = _error_arrays(manifold, tr.Fx[lo:hi], F[lo:hi], dims)
            err_y = np.linalg.norm(trajectory_y(manifold, tr)[lo:hi] - Y_true, axis=1)
            a = acc[m]
            a["sq"] += float((err ** 2).sum())
            a["sq_y"] += float((err_y ** 2).sum())
            a["n"] += hi - lo
            a["pt_sum"] += float(pe.sum())
            a["pt_n"] += pe.size
            a["pt_max"] = max(a["pt_max"], float(pe.max()))
            a["hat"].append(Xh[:, :3])
            a["true"].append(X_true[:, :3])
            a["utts"] += 1
            a["missed"] += sum(1 for w in tr.warnings if "unreachable" in w or "no path" in w)
            per_utt.append({"utterance": uid, "method": m, "frames": hi - lo,
                            "rmse_x": float(np.sqrt((err ** 2).mean())), "mean_point_error": float(pe.mean()),
                            "rmse_y": float(np.sqrt((err_y ** 2).mean()))})
    report(progress, "evaluation", len(test), len(test))
    rows = []
    for m in methods:
        a = acc[m]
        row = {"method": m, "utterances": a["utts"], "frames": a["n"], "failures": len(failures[m]),
               "missed_targets": a["missed"]}
        if a["n"]:
            H, T = np.vstack(a["hat"]), np.vstack(a["true"])
            row.update(rmse_x=float(np.sqrt(a["sq"] / a["n"])), mean_point_error=a["pt_sum"] / a["pt_n"],
                       max_point_error=a["pt_max"], rmse_y=float(np.sqrt(a["sq_y"] / a["n"])))
            for c in range(3):
                row[f"corr_{c + 1}"] = _corr(H[:, c], T[:, c]) if c < H.shape[1] else float("nan")
        else:
            row.update(rmse_x=float("nan"), mean_point_error=float("nan"), max_point_error=float("nan"),
                       rmse_y=float("nan"), corr_1=float("nan"), corr_2=float("nan"), corr_3=float("nan"))
        rows.append({c: row[c] for c in _COLUMNS})
    return EvaluationResult(rows=rows, test_ids=test, train_ids=train_ids, n_train_frames=train.n_frames,
                            per_utterance=per_utt, failures=failures, corpus=corpus.name)


def _corr(a, b) -> float:
    sa, sb = a.std(), b.std()
    if sa == 0 or sb == 0:
        return float("nan")
    return float(((a - a.mean()) * (b - b.mean())).mean() / (sa * sb))
