"""The result of :func:`engine.evaluation.protocols.evaluate_protocols`: tables, paired statistics, text, Markdown, CSV.

Aggregates pool frames over utterances (RMS over all compared frames; LVE averaged
over all compared frames). Each non-reference method is compared with ``manifold``
utterance by utterance (:func:`engine.evaluation.paired.paired_comparison`): a positive mean
difference means the manifold erred less. With a single test utterance there is nothing
to pair over utterances; X and LVE are then compared gap by gap (the frames from one
target to the next, each gap's RMSE X and mean LVE), so a one-sentence corpus still
gets an interval and a test -- of that sentence's gaps, which are not independent
utterances and say nothing about other sentences or speakers. A table's *verdict* names
every method whose pooled error is below the manifold's -- where the manifold loses, it
says so.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from engine.evaluation.paired import paired_comparison

__all__ = ["ProtocolResult", "CSV_COLUMNS"]

#: columns of :meth:`ProtocolResult.csv_rows`
CSV_COLUMNS = ("protocol", "method", "utterance", "rmse_x", "rmse_y", "lve", "vel", "smooth")
#: measures compared utterance by utterance (``smooth`` is descriptive: neither higher nor lower is better)
_MEASURES = ("rmse_x", "rmse_y", "lve", "vel")
#: measures that a one-utterance test compares gap by gap (the frames between two targets)
_GAP_MEASURES = ("rmse_x", "lve")
_LABEL = {"rmse_x": "RMSE X", "rmse_y": "RMSE Y3", "lve": "LVE", "vel": "vel. error"}
REFERENCE = "manifold"


@dataclass
class ProtocolResult:
    """Per-protocol tables of a held-out evaluation.

    Attributes
    ----------
    rows : list of dict
        ``protocol, method, utterances, frames, rmse_x, rmse_y, lve, vel, smooth`` (pooled).
    per_utterance : list of dict
        ``protocol, method, utterance, frames, rmse_x, rmse_y, lve, vel, smooth``.
    comparisons : list of dict
        ``protocol, method, measure`` and the fields of :class:`engine.evaluation.paired.PairedComparison`
        (method against ``manifold``; positive mean difference: manifold better).
    inverse_rows : list of dict
        ``map, frames, rmse_x, lve``: held-out frames' X reconstructed from their own F^y.
    settings : dict
        What :func:`engine.evaluation.protocols.select_settings` chose (or was given).
    """

    rows: list
    per_utterance: list
    comparisons: list
    inverse_rows: list
    settings: dict
    corpus: str = ""
    test_ids: list = field(default_factory=list)
    train_ids: list = field(default_factory=list)
    n_train_frames: int = 0
    n_states: int = 0
    failures: list = field(default_factory=list)
    missed_gaps: int = 0
    state_warnings: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    #: the manifold fitted on the training utterances (for further analysis; not part of any output)
    manifold: object = field(default=None, repr=False)
    #: each fold's settings when merged from folds (:meth:`merge`)
    folds: list = field(default_factory=list)
    #: the per-utterance sums the rows pool (for :meth:`merge`)
    _sums: list = field(default_factory=list, repr=False)

    # ---------------------------------------------------------------- building
    @classmethod
    def build(cls, per, *, n_boot, random_state, inverse, **kw):
        """From per-utterance sums (:func:`engine.synthesis.protocol_methods.scores` plus protocol, method,
        utterance)."""
        rows, comps = [], []
        keys = list(dict.fromkeys((p["protocol"], p["method"]) for p in per))
        slim = [_per_utterance(p) for p in per]
        for proto, m in keys:
            ps = [p for p in per if p["protocol"] == proto and p["method"] == m]
            rows.append({"protocol": proto, "method": m, "utterances": len(ps), **_pooled(ps)})
        raw = {(p["protocol"], p["method"], p["utterance"]): p for p in per}
        for proto in dict.fromkeys(k[0] for k in keys):
            ref = {p["utterance"]: p for p in slim if p["protocol"] == proto and p["method"] == REFERENCE}
            for _, m in [k for k in keys if k[0] == proto and k[1] != REFERENCE]:
                other = {p["utterance"]: p for p in slim if p["protocol"] == proto and p["method"] == m}
                uids = [u for u in ref if u in other]
                for meas in _MEASURES:
                    a, b, unit = [ref[u][meas] for u in uids], [other[u][meas] for u in uids], "utterances"
                    if len(uids) == 1 and meas in _GAP_MEASURES:
                        ga, gb = (_gap_errors(raw.get((proto, x, uids[0])), meas) for x in (REFERENCE, m))
                        if ga is not None and gb is not None and ga.size >= 2:
                            a, b, unit = ga, gb, "gaps"
                    c = paired_comparison(a, b, n_boot=n_boot, random_state=random_state)
                    comps.append({"protocol": proto, "method": m, "measure": meas, **c.as_dict(), "unit": unit})
        inv = [{"map": k, "frames": v["frames"], "rmse_x": float(np.sqrt(v["sq_x"] / v["frames"])),
                "lve": v["lve_sum"] / v["frames"],
                "r2": [float(x)
                       for x in 1.0 - np.asarray(v["sq_comp"]) / np.maximum(np.asarray(v["var_comp"]), 1e-300)]}
               for k, v in inverse.items() if not k.startswith("_")]
        out = cls(rows=rows, per_utterance=slim, comparisons=comps, inverse_rows=inv, **kw)
        out._sums = list(per)
        return out

    @classmethod
    def merge(cls, results, *, n_boot, random_state, notes=()):
        """One result from several folds (each held out other utterances): rows and tests over all of them.

        Settings, warnings and inverse rows are those of the first fold; ``folds`` keeps each fold's settings.
        """
        per = [p for r in results for p in r._sums]
        first = results[0]
        out = cls.build(per, n_boot=n_boot, random_state=random_state, inverse={}, corpus=first.corpus,
                        test_ids=[u for r in results for u in r.test_ids], train_ids=first.train_ids,
                        n_train_frames=first.n_train_frames, settings=first.settings,
                        failures=[f for r in results for f in r.failures],
                        missed_gaps=sum(r.missed_gaps for r in results), n_states=first.n_states,
                        state_warnings=list(dict.fromkeys(w for r in results for w in r.state_warnings)),
                        notes=list(notes), manifold=None)
        out.folds = [r.settings for r in results]
        out._sums = per
        return out

    # ---------------------------------------------------------------- access
    def row(self, protocol, method) -> dict:
        for r in self.rows:
            if r["protocol"] == protocol and r["method"] == method:
                return dict(r)
        raise KeyError(f"no ({protocol!r}, {method!r}) row; rows: {[(r['protocol'], r['method']) for r in self.rows]}")

    def comparison(self, protocol, method, measure="rmse_x") -> dict:
        for c in self.comparisons:
            if (c["protocol"], c["method"], c["measure"]) == (protocol, method, measure):
                return dict(c)
        raise KeyError(f"no comparison of {method!r} in protocol {protocol!r} on {measure!r}")

    def protocols(self) -> list[str]:
        return list(dict.fromkeys(r["protocol"] for r in self.rows))

    def verdict(self, protocol, measure="rmse_x") -> str:
        """One sentence: does ``manifold`` beat every other method of ``protocol`` on ``measure``?"""
        ref = self.row(protocol, REFERENCE)[measure]
        better = [r for r in self.rows if r["protocol"] == protocol and r["method"] != REFERENCE
                  and r[measure] < ref]
        if not better:
            return f"manifold has the lowest {_LABEL[measure]} of this protocol ({ref:.4g})."
        parts = []
        for r in sorted(better, key=lambda r: r[measure]):
            c = self.comparison(protocol, r["method"], measure)
            parts.append(f"{r['method']} ({r[measure]:.4g}, {100 * (ref - r[measure]) / ref:.0f} % lower; "
                         f"better on {c['losses']} of {c['n']} {c.get('unit', 'utterances')}, sign test p = "
                         f"{c['p_sign']:.2g}, signed-rank p = {c['p_wilcoxon']:.2g})")
        return f"manifold ({ref:.4g}) LOSES on {_LABEL[measure]} to " + "; ".join(parts) + "."

    # ---------------------------------------------------------------- output
    def csv_rows(self) -> list[dict]:
        """Per-utterance rows plus one pooled row per method (utterance ``ALL``), :data:`CSV_COLUMNS`."""
        out = [{k: p[k] for k in CSV_COLUMNS} for p in self.per_utterance]
        out += [{**{k: r[k] for k in CSV_COLUMNS if k != "utterance"}, "utterance": "ALL"} for r in self.rows]
        return [{k: r[k] for k in CSV_COLUMNS} for r in out]

    def _header(self) -> list[str]:
        s = self.settings
        sig = ", ".join(f"{k} {v:g}" for k, v in s.get("sigma", {}).items())
        per = "" if s.get("frames_per_state") is None else f" (one per {s['frames_per_state']} training frames)"
        lines = [f"held-out synthesis on {self.corpus}: {len(self.test_ids)} test utterance(s), "
                 f"{len(self.train_ids)} training ({self.n_train_frames} frames)",
                 f"states: {self.n_states} K-means states"
                 f"{per} of the first {s['state_dims']} dims of F^y; local-linear "
                 f"inverse k = {s['n_neighbors']}; Viterbi smoothing (frames) {sig}; {s.get('note', '')}"]
        for p, w in (s.get("blend") or {}).items():
            lines.append(f"manifold, {p}: {_blend_summary(w)}")
        if s.get("sliding_window"):
            ctx, ow, alpha = s["sliding_window"]
            lines.append(f"sliding-window regression: input ±{ctx} frames (every 2nd), output window {ow} frames, "
                         f"ridge alpha {alpha:g}")
        if s.get("best"):
            lines.append("best on validation (the explorer's and synthesize's default): "
                         + ", ".join(f"{p} {m}" for p, m in s["best"].items()))
        if self.missed_gaps:
            lines.append(f"{self.missed_gaps} gap(s) could not reach their target state in time (ended at the "
                         f"nearest reachable state)")
        lines += self.notes
        for w in self.state_warnings:
            lines.append(f"state graph: {w}")
        if self.failures:
            lines.append(f"{len(self.failures)} utterance(s) not scored, e.g. {self.failures[0]}")
        gaps = [c["n"] for c in self.comparisons if c.get("unit") == "gaps"]
        if gaps:
            lines.append(f"one test utterance: the intervals, wins and tests of X and LVE are over its "
                         f"{max(gaps)} gaps between targets (those of Y3 and velocity cannot be paired)")
        return lines

    def _table(self, protocol):
        head = ["method", "RMSE X", "RMSE Y3", "LVE", "vel. error", "smoothness", "ΔX vs manifold [95% CI]",
                "manifold wins X / LVE", "p X (sign, signed-rank)", "p LVE (sign, signed-rank)"]
        body = []
        for r in [r for r in self.rows if r["protocol"] == protocol]:
            cells = [r["method"], f"{r['rmse_x']:.4g}", f"{r['rmse_y']:.4g}", f"{r['lve']:.4g}", f"{r['vel']:.4g}",
                     f"{r['smooth']:.2f}"]
            if r["method"] == REFERENCE:
                body.append(cells + ["(reference)", "", "", ""])
                continue
            c = self.comparison(protocol, r["method"])
            cl = self.comparison(protocol, r["method"], "lve")
            ci = "" if not np.isfinite(c["ci_low"]) else f" [{c['ci_low']:+.3g}, {c['ci_high']:+.3g}]"
            body.append(cells + [f"{c['mean_diff']:+.3g}{ci}", f"{c['wins']}/{c['n']} / {cl['wins']}/{cl['n']}",
                                 f"{c['p_sign']:.2g}, {c['p_wilcoxon']:.2g}",
                                 f"{cl['p_sign']:.2g}, {cl['p_wilcoxon']:.2g}"])
        return head, body

    def format(self) -> str:
        """All tables as aligned text."""
        out = self._header()
        for p in self.protocols():
            head, body = self._table(p)
            w = [max(len(h), *(len(b[i]) for b in body)) for i, h in enumerate(head)]

            def fmt(row, w=w):
                return "  ".join(s.rjust(w[i]) if i else s.ljust(w[i]) for i, s in enumerate(row))

            out += ["", f"protocol {p!r}", fmt(head), fmt(["-" * x for x in w])] + [fmt(b) for b in body]
            out += [f"verdict X: {self.verdict(p, 'rmse_x')}", f"verdict Y: {self.verdict(p, 'rmse_y')}",
                    f"verdict LVE: {self.verdict(p, 'lve')}", f"verdict velocity: {self.verdict(p, 'vel')}"]
        if self.inverse_rows:
            out += ["", "inverse maps: held-out frames' X from their own F^y (R^2 per X component)",
                    "map  RMSE X  LVE  R^2"]
            out += [f"{r['map']}  {r['rmse_x']:.4g}  {r['lve']:.4g}  " + " ".join(f"{x:.2f}" for x in r["r2"])
                    for r in self.inverse_rows]
        return "\n".join(out)

    def markdown(self, *, title=None, level=3) -> str:
        """All tables as Markdown (for docs/RESULTS.md)."""
        h = "#" * level
        out = [f"{h} {title or self.corpus}", ""] + [f"- {line}" for line in self._header()] + [""]
        for p in self.protocols():
            head, body = self._table(p)
            out += [f"{h}# Protocol `{p}`", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
            out += ["| " + " | ".join(b) + " |" for b in body]
            out += ["", f"- X: {self.verdict(p, 'rmse_x')}", f"- Y: {self.verdict(p, 'rmse_y')}",
                    f"- LVE: {self.verdict(p, 'lve')}", f"- velocity: {self.verdict(p, 'vel')}", ""]
        if self.inverse_rows:
            nc = min(6, len(self.inverse_rows[0]["r2"]))
            out += [f"{h}# Inverse maps (held-out frames' X from their own F^y)", "",
                    "| map | RMSE X | LVE | " + " | ".join(f"R² X{j + 1}" for j in range(nc)) + " |",
                    "|---|---|---|" + "---|" * nc]
            out += [f"| {r['map']} | {r['rmse_x']:.4g} | {r['lve']:.4g} | "
                    + " | ".join(f"{x:.3f}" for x in r["r2"][:nc]) + " |" for r in self.inverse_rows]
            out.append("")
        return "\n".join(out)


def _pooled(ps) -> dict:
    """Pooled figures over per-utterance sums: RMS over all frames, LVE averaged over frames."""
    n = sum(p["frames"] for p in ps)
    nv = sum(p["frames_v"] for p in ps)
    at = sum(p["acc_true"] for p in ps)
    out = {"frames": n, "rmse_x": float(np.sqrt(sum(p["sq_x"] for p in ps) / n)),
           "lve": sum(p["lve_sum"] for p in ps) / n,
           "vel": float(np.sqrt(sum(p["sq_v"] for p in ps) / max(nv, 1))),
           "smooth": float(np.sqrt(sum(p["acc"] for p in ps) / at)) if at > 0 else float("nan")}
    out["rmse_y"] = (float(np.sqrt(sum(p["sq_y"] for p in ps) / n)) if all("sq_y" in p for p in ps)
                     else float("nan"))
    return out


def _gap_errors(p, measure):
    """Per gap between targets of one scored utterance (:func:`engine.synthesis.protocol_methods.scores` with
    ``gaps``): its RMSE X or mean LVE; None without gap sums."""
    if p is None or "gap_frames" not in p:
        return None
    n = np.asarray(p["gap_frames"], dtype=np.float64)
    if measure == "rmse_x":
        return np.sqrt(np.asarray(p["gap_sq_x"], dtype=np.float64) / n)
    return np.asarray(p["gap_lve"], dtype=np.float64) / n


def _per_utterance(p) -> dict:
    return {"protocol": p["protocol"], "method": p["method"], "utterance": p["utterance"], **_pooled([p])}


def _blend_summary(w) -> str:
    """The manifold method's validated weights in words: per component the base, the share and the paths pooled."""
    from engine.synthesis.learnt_paths import BASES, NEIGHBOR_STEPS

    beta = np.asarray(w["beta"], dtype=np.float64)
    bases = [BASES[i] for i in (w.get("base_index") or [0] * beta.size)]
    if not np.any(beta > 0) and set(bases) == {"hermite"}:
        return "no learnt share (the state-velocity Hermite spline)"
    if not np.any(beta > 0) and set(bases) == {"calibrated"}:
        return ("no learnt share (the Hermite spline with the state velocities calibrated on the targets' observed X; "
                "through the states' own means, the state-velocity Hermite spline)")
    ks = [NEIGHBOR_STEPS[i] for i in w["neighbor_index"]]
    parts = [f"X{j + 1} {b} + {s:.2f}×{k}" for j, (b, s, k) in enumerate(zip(bases, beta, ks))][:6]
    counts = ", ".join(f"{bases.count(b)} {b}" for b in BASES if b in bases)
    more = f", … ({beta.size} components: {counts}; mean share {beta.mean():.2f})" if beta.size > 6 else ""
    return "base + learnt share × paths pooled, per component: " + ", ".join(parts) + more
