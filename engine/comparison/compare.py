"""Two conditions on one manifold: where and how the levels of a field move differently.

:class:`ConditionComparison` fits nothing new on the manifold: both levels' frames are
already on it, with one set of states, clusters and tangent frames. For each contrast
(level b against level a of one field) it resolves the design
(:mod:`engine.comparison.design`), builds three families of statistics from per-utterance
sums -- the clusters (:mod:`engine.comparison.cluster_shift`), the dynamics
(:mod:`engine.comparison.dynamics`) and the states (:mod:`engine.comparison.enrichment`) --
and resamples whole units for their p-values and intervals
(:mod:`engine.comparison.statistics`). q-values are Benjamini-Hochberg within each family,
over every contrast of the fit. Every row states its design.
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np

from engine.comparison.cluster_shift import SPACES, cluster_family
from engine.comparison.design import ComparisonError, resolve_design
from engine.comparison.dynamics import dynamics_family, utterance_dynamics
from engine.comparison.enrichment import enrichment_family, state_counts
from engine.comparison.fields import level_counts
from engine.comparison.statistics import bh_qvalues, run_families
from engine.comparison.table import COLUMNS, FAMILIES
from engine.constraints import Interval, StrOptions, validate_params
from engine.estimator import Estimator, check_is_fitted

__all__ = ["ConditionComparison", "COLUMNS", "FAMILIES", "default_contrasts"]


def default_contrasts(values, by: str, levels=None) -> list[tuple[str, str]]:
    """The contrasts to fit: ``levels`` (a reference then one or more others: each against the
    reference), or the field's two levels in alphabetical order. Raises ComparisonError for a field with
    one level, or with more than two and no choice."""
    counts = level_counts(values)
    have = ", ".join(f"{k} ({v})" for k, v in counts.items()) or "none"
    if levels is not None:
        levels = [str(x) for x in levels]
        if len(levels) < 2:
            raise ComparisonError(f"field {by!r}: give at least two levels (a reference, then the levels compared "
                                  f"with it); its levels (utterances): {have}")
        if len(set(levels)) != len(levels):
            raise ComparisonError(f"field {by!r}: a level is given twice in {', '.join(levels)}")
        return [(levels[0], b) for b in levels[1:]]
    if len(counts) < 2:
        raise ComparisonError(f"field {by!r} has {'one level' if counts else 'no values'} ({have}); a comparison "
                              "needs two levels")
    if len(counts) > 2:
        raise ComparisonError(f"field {by!r} has {len(counts)} levels: {have}; choose two (A,B), or a reference "
                              "and the levels to compare with it (REF,B,C)")
    a, b = sorted(counts)
    return [(a, b)]


class ConditionComparison(Estimator):
    """Compare levels of a per-utterance field on one fitted manifold.

    Parameters
    ----------
    n_permutations : int, default=4999
        Random permutations per contrast (every arrangement when there are at most this many).
    n_bootstrap : int, default=1000
        Bootstrap draws for the intervals (0: none).
    confidence : float, default=0.95
    alpha : float, default=0.05
        The q-value a row must fall below to count as significant, and the p-value a design
        must be able to reach to be tested at all.
    horizon_s : float, default=0.1
        Horizon of the future hemisphere (s).
    n_dims : int, default=3
        Dimensions of Y and shape components of X the clusters are compared in.
    min_count : int, default=3
        Members a cluster needs in each level to be compared.
    labels : {"auto", "phones", "kinematic"}, default="auto"
        Clusters of phone mid-points or of kinematic landmarks
        (:func:`engine.manifold.clusters.clusters_of`).
    random_state : int, default=0

    Attributes
    ----------
    contrasts_ : list of (str, str)
    designs_ : list of Design, one per contrast
    rows_ : list of dict
        One per comparison, keys :data:`COLUMNS`.
    enrichment_, enrichment_p_, enrichment_q_ : ndarray of shape (n_contrasts, K)
        Per state: log2 occupancy ratio (level b over a), p and q.
    occupancy_a_, occupancy_b_ : ndarray of shape (n_contrasts, K)
        Share (%) of each level's frames in each state.
    clusters_ : PhoneClusters or None
    cluster_kind_ : {"phones", "kinematic", ""}
    notes_ : list of str
    """

    _parameter_constraints = {
        "n_permutations": [Interval(Integral, 1, None, closed="left")],
        "n_bootstrap": [Interval(Integral, 0, None, closed="left")],
        "confidence": [Interval(Real, 0, 1, closed="neither")],
        "alpha": [Interval(Real, 0, 1, closed="neither")],
        "horizon_s": [Interval(Real, 0, None, closed="neither")],
        "n_dims": [Interval(Integral, 1, None, closed="left")],
        "min_count": [Interval(Integral, 2, None, closed="left")],  # a covariance needs two members
        "labels": [StrOptions({"auto", "phones", "kinematic"})],
        "random_state": [Interval(Integral, 0, 2**32 - 1, closed="both")],  # a SeedSequence entry
    }

    def __init__(self, *, n_permutations=4999, n_bootstrap=1000, confidence=0.95, alpha=0.05, horizon_s=0.1,
                 n_dims=3, min_count=3, labels="auto", random_state=0):
        self.n_permutations = n_permutations
        self.n_bootstrap = n_bootstrap
        self.confidence = confidence
        self.alpha = alpha
        self.horizon_s = horizon_s
        self.n_dims = n_dims
        self.min_count = min_count
        self.labels = labels
        self.random_state = random_state

    def fit(self, manifold, levels, *, by: str = "level", contrasts=None, speakers=None, pairs=None,
            paired_by: str = "", progress=None):
        """Compare the levels.

        Parameters
        ----------
        manifold : engine.manifold.model.Manifold, fitted on every level's utterances
        levels : sequence of str, length n_utterances
            The compared field's value of each utterance ("" unknown: left out).
        by : str
            The field's name (``"speaker"`` compares speakers as individuals).
        contrasts : list of (level_a, level_b) or None
            None: the field's two levels (:func:`default_contrasts`).
        speakers : sequence of str or None
            Each utterance's speaker (default: ``Utterance.speaker``).
        pairs : sequence of str or None
            The pairing field's values (with ``paired_by``).
        paired_by : str
            Name of the pairing field ("" = unpaired).
        progress : callable(stage, done, total) or None

        Returns
        -------
        self
        """
        validate_params(self)
        c = manifold.corpus_
        n_utt = len(c.utterances)
        levels = np.asarray(["" if v is None else str(v) for v in levels], dtype=str)
        if levels.shape != (n_utt,):
            raise ValueError(f"levels has {levels.size} values for {n_utt} utterances of {c.name}; give one per "
                             "utterance")
        if speakers is None:
            speakers = [u.speaker for u in c.utterances]
        contrasts = default_contrasts(levels, by) if contrasts is None else [(str(a), str(b)) for a, b in contrasts]
        designs = [resolve_design(levels, a, b, by=by, speakers=speakers, pairs=pairs, paired_by=paired_by,
                                  alpha=self.alpha) for a, b in contrasts]
        uidx = c.utterance_index
        notes = []
        normalised = [h for h in c.history if h.startswith("speaker normalisation")]
        if normalised and (by == "speaker" or any(d.kind == "between speakers" for d in designs)):
            notes.append(f"the manifold was fitted after {normalised[-1].split(':')[0]}: each speaker's mean lip shape "
                         "was removed first, so a difference between the speakers' average shapes is not part of "
                         "this comparison; how they move about it is")
        clusters, kind = self._clusters(manifold, notes)
        dyn = utterance_dynamics(manifold, horizon_s=self.horizon_s, progress=progress)
        K = manifold.states_.centroids_.shape[0]
        counts = state_counts(manifold.states_.labels_, uidx, n_utt, K)
        rows, enrich = [], []
        for i, design in enumerate(designs):
            families = [dynamics_family(dyn, design.utterances), enrichment_family(counts, design.utterances)]
            if clusters is not None:
                scale = 1.0 / np.sqrt(c.n_points)
                families += [cluster_family(clusters, manifold.Fy_, uidx, design.utterances, space="Y",
                                            n_dims=self.n_dims),
                             cluster_family(clusters, manifold.Fx_, uidx, design.utterances, space="X",
                                            n_dims=self.n_dims, scale=scale)]
            results = run_families(design, families, n_permutations=self.n_permutations,
                                   n_bootstrap=self.n_bootstrap, confidence=self.confidence,
                                   random_state=self._seed(i), progress=progress)
            text = self._design_text(design, results[0])
            rows += self._dynamics_rows(design, dyn, families[0], results[0], text)
            state_rows, lr = self._state_rows(design, families[1], results[1], text, K)
            rows += state_rows
            enrich.append(lr)
            if clusters is not None:
                rows += self._cluster_rows(design, clusters, families[2:], results[2:], text, c, notes)
        for fam in FAMILIES:
            idx = [k for k, r in enumerate(rows) if r["family"] == fam]
            q = bh_qvalues([rows[k]["p"] for k in idx])
            for k, qk in zip(idx, q):
                rows[k]["q"] = float(qk)
        self.contrasts_ = contrasts
        self.designs_ = designs
        self.rows_ = rows
        nc = len(designs)
        state_rows = [r for r in rows if r["family"] == "state"]
        grid = {name: np.full((nc, K), np.nan) for name in ("estimate", "p", "q", "value_a", "value_b")}
        for r in state_rows:
            i = contrasts.index((r["level_a"], r["level_b"]))
            for name, arr in grid.items():
                arr[i, int(r["target"])] = r[name]
        self.enrichment_, self.enrichment_p_, self.enrichment_q_ = grid["estimate"], grid["p"], grid["q"]
        self.occupancy_a_, self.occupancy_b_ = grid["value_a"], grid["value_b"]
        self.clusters_, self.cluster_kind_ = clusters, kind
        self.notes_ = notes + [n for d in designs for n in d.notes]
        self.by_, self.paired_by_ = str(by), str(paired_by or "")
        return self

    # ---------------------------------------------------------------------------- pieces
    def _seed(self, i):
        return np.random.SeedSequence([int(self.random_state), i])

    def _clusters(self, manifold, notes):
        from engine.manifold.clusters import clusters_of

        try:
            pc, kind, note = clusters_of(manifold, labels=self.labels, n_dims=self.n_dims, min_count=self.min_count)
        except ValueError as exc:
            notes.append(f"no clusters compared: {exc}")
            return None, ""
        if note:
            notes.append(note)
        if not pc.phones_:
            notes.append(f"no cluster has {self.min_count} or more members: no clusters compared")
            return None, kind
        return pc, kind

    def _design_text(self, design, result) -> str:
        text = design.describe()
        if not design.testable:
            return text
        perm = (f"exact: all {result.n_permutations} arrangements" if result.exact
                else f"{result.n_permutations} permutations")
        boot = (f"bootstrap over {'blocks' if design.bootstrap == 'blocks' else design.unit_name + 's'} "
                f"({self.n_bootstrap} draws)" if design.can_bootstrap and self.n_bootstrap else "no interval")
        return f"{text}; {perm}; {boot}"

    def _base(self, design, family, measure, target, space, unit, text) -> dict:
        return {"field": design.by, "level_a": design.level_a, "level_b": design.level_b, "family": family,
                "measure": measure, "target": str(target), "space": space, "unit": unit, "design": text}

    @staticmethod
    def _numbers(result, j, m) -> dict:
        return {"estimate": float(result.estimate[j]), "ci_low": float(result.ci_low[j]),
                "ci_high": float(result.ci_high[j]), "p": float(result.p[j]), "q": float("nan"),
                "value_a": float(result.estimate[m + j]) if m is not None else float("nan"),
                "value_b": float(result.estimate[2 * m + j]) if m is not None else float("nan")}

    @staticmethod
    def _counts(design, present) -> dict:
        """n_utterances (a, b) and n_speakers of the design's utterances where ``present`` (U,) is True."""
        g = design.group
        spk = design.speakers[present]
        return {"n_utterances": int(present.sum()), "n_utterances_a": int((present & (g == 0)).sum()),
                "n_utterances_b": int((present & (g == 1)).sum()), "n_speakers": int(len(set(spk.tolist())))}

    def _dynamics_rows(self, design, dyn, family, result, text) -> list:
        M = dyn.numerator.shape[1]
        den = np.asarray(family.S)[:, M:]
        rows = []
        for j in range(M):
            r = self._base(design, "dynamics", dyn.measures[j], dyn.targets[j], "", f"ratio ({dyn.units[j]})", text)
            r.update(self._numbers(result, j, M), **self._counts(design, den[:, j] > 0))
            rows.append(r)
        return rows

    def _state_rows(self, design, family, result, text, K):
        present = (family.S > 0).tocsc()
        rows = []
        for k in range(K):
            r = self._base(design, "state", "enrichment", k, "Y", "log2 occupancy ratio", text)
            col = np.zeros(family.S.shape[0], bool)
            col[present.indices[present.indptr[k]:present.indptr[k + 1]]] = True
            r.update(self._numbers(result, k, K), **self._counts(design, col))
            rows.append(r)
        return rows, np.asarray(result.estimate[:K])

    def _cluster_rows(self, design, clusters, families, results, text, corpus, notes) -> list:
        C = len(clusters.phones_)
        rows, few = [], []
        unit_x = f"{corpus.unit_label} per point (RMS)"
        for space, family, result in zip(SPACES, families, results):
            d = family.S.shape[1] // C
            present = family.S.reshape(-1, C, d)[..., 0] > 0
            na, nb = result.estimate[2 * C:3 * C], result.estimate[3 * C:4 * C]
            for ci, phone in enumerate(clusters.phones_):
                if min(na[ci], nb[ci]) < self.min_count:
                    if space == "Y":
                        few.append(f"{phone} ({int(na[ci])}/{int(nb[ci])})")
                    continue
                cnt = self._counts(design, present[:, ci])
                shift = self._base(design, "cluster", "centre shift", phone, space,
                                   "s.d. (pooled within level)" if space == "Y" else unit_x, text)
                shift.update(self._numbers(result, ci, None), value_a=float(na[ci]), value_b=float(nb[ci]), **cnt)
                spread = self._base(design, "cluster", "spread ratio", phone, space, "ratio (level b / level a)", text)
                spread.update(self._numbers(result, C + ci, None), value_a=float(na[ci]), value_b=float(nb[ci]),
                              **cnt)
                rows += [shift, spread]
        if few:
            notes.append(f"{design.level_b} vs {design.level_a}: clusters with fewer than {self.min_count} members "
                         f"in a level (members {design.level_a}/{design.level_b}) not compared: {', '.join(few)}")
        return rows

    # ---------------------------------------------------------------------------- reading
    def table(self, *, family=None, contrast=None) -> list[dict]:
        """The rows (copies), optionally of one family and one contrast (index into ``contrasts_``)."""
        check_is_fitted(self, "rows_")
        out = []
        for r in self.rows_:
            if family is not None and r["family"] != family:
                continue
            if contrast is not None and (r["level_a"], r["level_b"]) != tuple(self.contrasts_[contrast]):
                continue
            out.append(dict(r))
        return out

    def significant(self, *, family=None, contrast=None) -> list[dict]:
        """Rows with q below ``alpha``, smallest q first."""
        rows = [r for r in self.table(family=family, contrast=contrast) if r["q"] < self.alpha]
        return sorted(rows, key=lambda r: (r["q"], r["p"]))

    @property
    def testable_(self) -> list[bool]:
        check_is_fitted(self, "designs_")
        return [d.testable for d in self.designs_]
