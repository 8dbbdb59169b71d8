"""Concatenative visual unit selection, the baseline of the second paper (Laureate-style).

Every target phone is realised by one phone instance of the training corpus (a
*unit*) seen in its N-phone context window (N = 3: one phone either side; N = 5: two).

Selection
    Candidates for a target phone are the corpus instances of the same phone, scored
    by context match -- left-context, right-context and full-context ("bias")
    conditions -- keeping up to ``max_candidates`` (the best of each condition, ties
    broken by the smallest duration change). Dynamic programming then picks the
    sequence minimising target cost + join cost. Target cost: ``1`` per mismatched
    neighbour at distance 1, ``0.5`` at distance 2 (N = 5). Join cost: ``0`` when the
    next unit is the corpus successor of the previous one; otherwise
    ``join_weight * ||F^x(end of unit a) - F^x(start of unit b)|| / r`` with ``r`` the
    RMS distance of the corpus frames from their mean in X.
Concatenation
    Each unit is time-warped piecewise-linearly so that its phone (and its context
    phones) span the target phones' intervals. A join is *soft* when the two units
    overlap -- the first unit's right neighbour in the corpus is the target's next
    phone and the second unit's left neighbour is the target's previous phone -- and
    *hard* (the units merely abut) otherwise.
    Soft joins crossfade over the overlap, from the mid-point of the forward phone to
    the mid-point of the backward phone; the crossfade's 50 % point lies at the
    forward share of Table 1 of the paper (:data:`OVERLAP_TABLE`, by the lip-reading
    classes protected / invisible / normal of the two joining phones): 50/50 is the
    middle, P/I 77/23 lets the protected phone's unit run 77 % of the way.
    Hard joins abut at the phone boundary and smooth the last 5 % of the first unit
    and the first 5 % of the second (at least one frame each) by linear
    interpolation across the boundary.
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np

from engine.constraints import Condition, Interval, Options, validate_params
from engine.estimator import Estimator, check_is_fitted
from engine.phonetics.targets import TargetSequence
from engine.synthesis.trajectory import Trajectory, check_fitted_manifold, target_frames
from engine.threads import single_blas_thread

__all__ = ["UnitSelectionSynthesizer", "OVERLAP_TABLE", "overlap_fraction", "crossfade_weights", "lip_class"]

#: Table 1 of the second paper: the forward (earlier) phone's share of the overlap, in percent,
#: by (forward class, backward class).
OVERLAP_TABLE = {
    ("protected", "protected"): 50, ("protected", "invisible"): 77, ("protected", "normal"): 55,
    ("invisible", "protected"): 23, ("invisible", "invisible"): 50, ("invisible", "normal"): 27,
    ("normal", "protected"): 45, ("normal", "invisible"): 77, ("normal", "normal"): 50,
}
_CLASSES = ("protected", "invisible", "normal")
_BOUNDARY = "#"


def lip_class(label: str) -> str:
    """Lip-reading class of a phone: "protected", "invisible" or "normal" (via engine.phonetics.phonesets).

    Pauses and labels no phone set knows count as "normal" (the second paper: every
    phone neither invisible nor protected is normal).
    """
    from engine.phonetics.phonesets import lipreading_class

    c = str(lipreading_class(label, strict=False)).lower()
    return c if c in _CLASSES else "normal"


def overlap_fraction(forward: str, backward: str) -> float:
    """Forward phone's share (0..1) of the overlap between two joining phones, by class (Table 1)."""
    try:
        return OVERLAP_TABLE[(forward, backward)] / 100.0
    except KeyError:
        raise ValueError(f"unknown lip-reading classes ({forward!r}, {backward!r}); "
                         f"expected two of {_CLASSES}") from None


def crossfade_weights(t, mid_a: float, mid_b: float, fraction: float) -> np.ndarray:
    """Weight of the backward unit at times ``t`` across the overlap ``[mid_a, mid_b]``.

    Piecewise linear: 0 at ``mid_a``, 0.5 at the crossfade point
    ``mid_a + fraction * (mid_b - mid_a)``, 1 at ``mid_b`` (0 before, 1 after).
    """
    t = np.asarray(t, dtype=np.float64)
    c = mid_a + fraction * (mid_b - mid_a)
    return np.interp(t, [mid_a, c, mid_b], [0.0, 0.5, 1.0])


class UnitSelectionSynthesizer(Estimator):
    """Concatenative unit selection over the training corpus's phone instances.

    Parameters
    ----------
    context : {3, 5}, default=3
        N of the N-phone context window.
    max_candidates : int, default=30
        Candidate units per target phone.
    join_weight : float, default=1.0
        Weight of the join cost relative to one context mismatch.
    exclude_utterances : sequence of str, optional
        Corpus utterances whose units may not be used (e.g. the one being resynthesised).
    smoothing : float, default=0.05
        Fraction of each unit smoothed at a hard join (the paper: 5 %); at least one
        frame each side when > 0; 0 abuts the units unsmoothed.
    """

    method = "unitselection"
    _parameter_constraints = {
        "context": [Options(Integral, (3, 5))],
        "max_candidates": [Interval(Integral, 1, None, closed="left")],
        "join_weight": [Interval(Real, 0, None, closed="left")],
        "exclude_utterances": [Condition(lambda v: isinstance(v, (list, tuple, set, frozenset))
                                         and all(isinstance(u, str) for u in v),
                                         "a list or tuple of utterance ids (str)", bad=["s0001", [1]]), None],
        "smoothing": [Interval(Real, 0, 0.5, closed="left")],
    }

    def __init__(self, *, context=3, max_candidates=30, join_weight=1.0, exclude_utterances=(), smoothing=0.05):
        self.context = context
        self.max_candidates = max_candidates
        self.join_weight = join_weight
        self.exclude_utterances = exclude_utterances
        self.smoothing = smoothing

    # ------------------------------------------------------------------ fitting
    def fit(self, manifold):
        """Index the phone instances of the manifold's training corpus."""
        validate_params(self)
        check_fitted_manifold(manifold)
        c = manifold.corpus_
        excl = set(self.exclude_utterances or ())
        lab, utt, pos, st, en = [], [], [], [], []
        for k, u in enumerate(c.utterances):
            for j, p in enumerate(u.phones):
                lab.append(p.label), utt.append(k), pos.append(j), st.append(p.start), en.append(p.end)
        if not lab:
            raise ValueError(f"{c.name} has no phone alignments; unit selection needs phone-aligned utterances "
                             "(import the corpus with an alignment)")
        lab = np.array(lab, dtype=str)
        utt = np.array(utt, dtype=np.int64)
        pos = np.array(pos, dtype=np.int64)
        ctx = {}
        for off in (-2, -1, 1, 2):
            j = np.arange(lab.size) + off
            ok = (j >= 0) & (j < lab.size)
            same = np.zeros(lab.size, dtype=bool)
            same[ok] = utt[j[ok]] == utt[ok]
            ctx[off] = np.where(same, lab[np.clip(j, 0, lab.size - 1)], _BOUNDARY)
        b = c.bounds
        Fx = np.asarray(manifold.Fx_)
        rate = c.rate
        f_st = np.clip(b[utt, 0] + np.round(np.array(st) * rate).astype(np.int64), b[utt, 0], b[utt, 1] - 1)
        f_en = np.clip(b[utt, 0] + np.round(np.array(en) * rate).astype(np.int64), b[utt, 0], b[utt, 1] - 1)
        self.labels_ = lab
        self.utterance_ = utt
        self.position_ = pos
        self.start_ = np.array(st, dtype=np.float64)
        self.end_ = np.array(en, dtype=np.float64)
        self.context_ = np.stack([ctx[o] for o in (-2, -1, 1, 2)], axis=1)  # (n_inst, 4)
        self.allowed_ = np.array([c.utterances[k].id not in excl for k in utt])
        self.start_x_ = Fx[f_st].astype(np.float64)
        self.end_x_ = Fx[f_en].astype(np.float64)
        self.scale_ = float(np.sqrt(((Fx - Fx.mean(axis=0)) ** 2).sum(axis=1).mean())) or 1.0
        self.bounds_ = b
        self.rate_ = float(rate)
        self._Fx = Fx
        self._ids = [u.id for u in c.utterances]
        return self

    # ------------------------------------------------------------------ selection
    def _target_context(self, labels):
        n = len(labels)
        padded = [_BOUNDARY, _BOUNDARY] + list(labels) + [_BOUNDARY, _BOUNDARY]
        return np.array([[padded[i + 2 + o] for o in (-2, -1, 1, 2)] for i in range(n)], dtype=object)

    def _candidates(self, i, label, tctx, tdur, warnings):
        idx = np.flatnonzero((self.labels_ == label) & self.allowed_)
        if idx.size == 0:  # a phone the corpus lacks: the closest phone in articulation stands in
            from engine.phonetics.targets import stand_in_phone

            labs, cnt = np.unique(self.labels_[self.allowed_], return_counts=True)
            sub = stand_in_phone(label, labs[np.argsort(-cnt, kind="stable")].tolist())
            if sub is None:
                raise ValueError(f"target phone {i} {label!r} has no usable unit in the corpus and no phone of its "
                                 f"class stands in; known phones: {' '.join(labs.tolist())}")
            warnings.append(f"phone {i} {label!r} has no unit in the corpus; {sub!r} units stand in")
            idx = np.flatnonzero((self.labels_ == sub) & self.allowed_)
        mism = self.context_[idx] != tctx[None, :].astype(str)  # (c, 4): offsets -2, -1, +1, +2
        w = np.array([0.5, 1.0, 1.0, 0.5]) if self.context == 5 else np.array([0.0, 1.0, 1.0, 0.0])
        left = mism[:, :2] @ w[:2]
        right = mism[:, 2:] @ w[2:]
        full = left + right
        dur = np.abs(np.log((self.end_[idx] - self.start_[idx]) / tdur))
        M = int(self.max_candidates)
        pick = []
        for key in (full, left, right):  # full / left / right context "bias" conditions
            order = np.lexsort((idx, dur, key))
            pick.extend(order[: max(1, M // 3)].tolist())
        order = np.lexsort((idx, dur, full))
        for o in order:
            if len(set(pick)) >= M:
                break
            pick.append(int(o))
        sel = np.array(sorted(set(pick)), dtype=np.int64)
        return idx[sel], full[sel]

    def _select(self, phones, warnings):
        labels = [p.label for p in phones]
        tctx = self._target_context(labels)
        cands, tcost = [], []
        for i, p in enumerate(phones):
            c, tc = self._candidates(i, p.label, tctx[i], p.end - p.start, warnings)
            cands.append(c), tcost.append(tc)
        cost = tcost[0].copy()
        backs = []
        jw = float(self.join_weight) / self.scale_
        for i in range(1, len(phones)):
            a, b = cands[i - 1], cands[i]
            J = jw * np.linalg.norm(self.end_x_[a][:, None, :] - self.start_x_[b][None, :, :], axis=2)
            succ = (self.utterance_[a][:, None] == self.utterance_[b][None, :]) & (
                self.position_[a][:, None] + 1 == self.position_[b][None, :])
            J[succ] = 0.0
            tot = cost[:, None] + J
            bi = np.argmin(tot, axis=0)
            cost = tot[bi, np.arange(b.size)] + tcost[i]
            backs.append(bi)
        j = int(np.argmin(cost))
        units = [0] * len(phones)
        units[-1] = int(cands[-1][j])
        for i in range(len(phones) - 2, -1, -1):
            j = int(backs[i][j])
            units[i] = int(cands[i][j])
        return np.array(units, dtype=np.int64), float(cost.min())

    # ------------------------------------------------------------------ rendering
    def _neighbour(self, unit, off):
        """Instance index of the corpus neighbour at ``off`` in the same utterance, or -1."""
        j = unit + off
        if 0 <= j < self.labels_.size and self.utterance_[j] == self.utterance_[unit]:
            return j
        return -1

    def _sample(self, unit, i, phones, t):
        """Unit ``unit`` (realising target phone ``i``) at target times ``t`` -> (len(t), m)."""
        knots_t, knots_s = [], []
        for off in (-1, 0, 1):
            k, j = i + off, self._neighbour(unit, off) if off else unit
            if 0 <= k < len(phones) and j >= 0:
                knots_t += [phones[k].start, phones[k].end]
                knots_s += [self.start_[j], self.end_[j]]
        kt, inv = np.unique(np.array(knots_t), return_inverse=True)  # shared boundaries: one knot
        ks = np.bincount(inv, weights=np.array(knots_s)) / np.bincount(inv)
        # linear extrapolation beyond the knots at the own phone's speed
        slope = (self.end_[unit] - self.start_[unit]) / (phones[i].end - phones[i].start)
        s = np.interp(t, kt, ks)
        s = np.where(t < kt[0], ks[0] + (t - kt[0]) * slope, s)
        s = np.where(t > kt[-1], ks[-1] + (t - kt[-1]) * slope, s)
        lo, hi = self.bounds_[self.utterance_[unit]]
        pos = np.clip(lo + s * self.rate_, lo, hi - 1)
        f0 = np.floor(pos).astype(np.int64)
        f1 = np.minimum(f0 + 1, hi - 1)
        w = (pos - f0)[:, None]
        return (1 - w) * self._Fx[f0] + w * self._Fx[f1]

    @single_blas_thread
    def synthesize(self, targets: TargetSequence) -> Trajectory:
        """Select units for ``targets.phones`` and concatenate them over ``targets.n_frames`` frames."""
        check_is_fitted(self, "labels_")
        phones = list(targets.phones)
        if not phones:
            raise ValueError("unit selection needs the phone intervals of the utterance (targets.phones is empty)")
        warnings: list[str] = []
        units, total = self._select(phones, warnings)
        n = int(targets.n_frames)
        rate = float(targets.rate)
        t = np.arange(n) / rate
        mids = np.array([p.mid for p in phones])
        classes = [lip_class(p.label) for p in phones]
        out = np.empty((n, self._Fx.shape[1]), dtype=np.float64)
        region = np.searchsorted(mids, t, side="right") - 1  # join region: between mids[r] and mids[r+1]
        first = region < 0
        if first.any():
            out[first] = self._sample(units[0], 0, phones, t[first])
        last = region >= len(phones) - 1
        if last.any():
            out[last] = self._sample(units[-1], len(phones) - 1, phones, t[last])
        joins = []
        hard_windows = []
        for i in range(len(phones) - 1):
            sel = region == i
            a, b = units[i], units[i + 1]
            contiguous = self._neighbour(a, 1) == b
            ra, lb = self._neighbour(a, 1), self._neighbour(b, -1)
            soft = contiguous or (ra >= 0 and lb >= 0 and self.labels_[ra] == phones[i + 1].label
                                  and self.labels_[lb] == phones[i].label)
            frac = overlap_fraction(classes[i], classes[i + 1])
            kind = "contiguous" if contiguous else ("soft" if soft else "hard")
            joins.append(kind)
            if not sel.any():
                if kind == "hard":
                    hard_windows.append(i)
                continue
            ts = t[sel]
            if soft:
                w = crossfade_weights(ts, mids[i], mids[i + 1], frac)[:, None]
                out[sel] = (1 - w) * self._sample(a, i, phones, ts) + w * self._sample(b, i + 1, phones, ts)
            else:
                before = ts < phones[i].end
                block = np.empty((ts.size, out.shape[1]))
                if before.any():
                    block[before] = self._sample(a, i, phones, ts[before])
                if (~before).any():
                    block[~before] = self._sample(b, i + 1, phones, ts[~before])
                out[sel] = block
                hard_windows.append(i)
        if float(self.smoothing) > 0:
            for i in hard_windows:
                self._smooth(out, phones, i, rate, float(self.smoothing))
        f = target_frames(targets) if targets.targets else np.zeros(0, dtype=np.int64)
        info = {"units": [(self._ids[self.utterance_[u]], int(self.position_[u])) for u in units],
                "joins": joins, "cost": total, "classes": classes}
        return Trajectory(times=t, Fx=out.astype(np.float32), Fy=None, method=self.method,
                          target_frames=f, target_labels=[x.label for x in targets.targets], info=info,
                          warnings=warnings)

    @staticmethod
    def _smooth(out, phones, i, rate, frac):
        """Linear smoothing across a hard join: the last ``frac`` of unit i and the first of unit i+1."""
        n = out.shape[0]
        kb = int(np.ceil(phones[i].end * rate - 1e-9))  # first frame of the second unit
        na = max(1, int(np.ceil(frac * (phones[i].end - phones[i].start) * rate)))
        nb = max(1, int(np.ceil(frac * (phones[i + 1].end - phones[i + 1].start) * rate)))
        A, B = kb - na - 1, kb + nb
        A, B = max(A, 0), min(B, n - 1)
        if B - A < 2:
            return
        w = (np.arange(A + 1, B) - A)[:, None] / (B - A)
        out[A + 1:B] = (1 - w) * out[A] + w * out[B]
