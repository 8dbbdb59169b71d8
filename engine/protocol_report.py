"""The result of :func:`engine.protocols.evaluate_protocols`: tables, paired statistics, text, Markdown, CSV.

Aggregates pool frames over utterances (RMS over all compared frames; LVE averaged
over all compared frames). Each non-reference method is compared with ``manifold``
utterance by utterance (:func:`engine.paired.paired_comparison`): a positive mean
difference means the manifold erred less. A table's *verdict* names every method
whose pooled error is below the manifold's -- where the manifold loses, it says so.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from engine.paired import paired_comparison

__all__ = ["ProtocolResult", "CSV_COLUMNS"]

#: columns of :meth:`ProtocolResult.csv_rows`
CSV_COLUMNS = ("protocol", "method", "utterance", "rmse_x", "rmse_y", "lve")
_MEASURES = ("rmse_x", "rmse_y", "lve")
_LABEL = {"rmse_x": "RMSE X", "rmse_y": "RMSE Y3", "lve": "LVE"}
REFERENCE = "manifold"


@dataclass
class ProtocolResult:
    """Per-protocol tables of a held-out evaluation.

    Attributes
    ----------
    rows : list of dict
        ``protocol, method, utterances, frames, rmse_x, rmse_y, lve`` (pooled).
    per_utterance : list of dict
        ``protocol, method, utterance, frames, rmse_x, rmse_y, lve``.
    comparisons : list of dict
        ``protocol, method, measure`` and the fields of :class:`engine.paired.PairedComparison`
        (method against ``manifold``; positive mean difference: manifold better).
    inverse_rows : list of dict
        ``map, frames, rmse_x, lve``: held-out frames' X reconstructed from their own F^y.
    settings : dict
        What :func:`engine.protocols.select_settings` chose (or was given).
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

    # ---------------------------------------------------------------- building
    @classmethod
    def build(cls, per, *, n_boot, random_state, inverse, **kw):
        rows, comps = [], []
        keys = list(dict.fromkeys((p["protocol"], p["method"]) for p in per))
        for proto, m in keys:
            ps = [p for p in per if p["protocol"] == proto and p["method"] == m]
            n = sum(p["frames"] for p in ps)
            rows.append({"protocol": proto, "method": m, "utterances": len(ps), "frames": n,
                         "rmse_x": float(np.sqrt(sum(p["sq_x"] for p in ps) / n)),
                         "rmse_y": float(np.sqrt(sum(p["sq_y"] for p in ps) / n)),
                         "lve": sum(p["lve_sum"] for p in ps) / n})
        for proto in dict.fromkeys(k[0] for k in keys):
            ref = {p["utterance"]: p for p in per if p["protocol"] == proto and p["method"] == REFERENCE}
            for _, m in [k for k in keys if k[0] == proto and k[1] != REFERENCE]:
                other = {p["utterance"]: p for p in per if p["protocol"] == proto and p["method"] == m}
                uids = [u for u in ref if u in other]
                for meas in _MEASURES:
                    c = paired_comparison([ref[u][meas] for u in uids], [other[u][meas] for u in uids],
                                          n_boot=n_boot, random_state=random_state)
                    comps.append({"protocol": proto, "method": m, "measure": meas, **c.as_dict()})
        inv = [{"map": k, "frames": v["frames"], "rmse_x": float(np.sqrt(v["sq_x"] / v["frames"])),
                "lve": v["lve_sum"] / v["frames"],
                "r2": [float(x) for x in 1.0 - np.asarray(v["sq_comp"]) / np.maximum(np.asarray(v["var_comp"]), 1e-300)]}
               for k, v in inverse.items() if not k.startswith("_")]
        slim = [{k: p[k] for k in ("protocol", "method", "utterance", "frames", "rmse_x", "rmse_y", "lve")}
                for p in per]
        return cls(rows=rows, per_utterance=slim, comparisons=comps, inverse_rows=inv, **kw)

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
                         f"better on {c['losses']} of {c['n']} utterances, sign test p = {c['p_sign']:.2g})")
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
        lines = [f"held-out synthesis on {self.corpus}: {len(self.test_ids)} test utterance(s), "
                 f"{len(self.train_ids)} training ({self.n_train_frames} frames)",
                 f"states: {self.n_states} K-means states"
                 f"{'' if s.get('frames_per_state') is None else ' (one per %s training frames)' % s['frames_per_state']}"
                 f" of the first {s['state_dims']} dims of F^y; local-linear "
                 f"inverse k = {s['n_neighbors']}; smoothing (frames) {sig}; {s.get('note', '')}"]
        if self.missed_gaps:
            lines.append(f"{self.missed_gaps} gap(s) could not reach their target state in time (ended at the "
                         f"nearest reachable state)")
        lines += self.notes
        for w in self.state_warnings:
            lines.append(f"state graph: {w}")
        if self.failures:
            lines.append(f"{len(self.failures)} utterance(s) not scored, e.g. {self.failures[0]}")
        return lines

    def _table(self, protocol):
        head = ["method", "RMSE X", "RMSE Y3", "LVE", "ΔX vs manifold [95% CI]", "manifold wins X", "p (sign)"]
        body = []
        for r in [r for r in self.rows if r["protocol"] == protocol]:
            if r["method"] == REFERENCE:
                body.append([r["method"], f"{r['rmse_x']:.4g}", f"{r['rmse_y']:.4g}", f"{r['lve']:.4g}",
                             "(reference)", "", ""])
                continue
            c = self.comparison(protocol, r["method"])
            ci = "" if not np.isfinite(c["ci_low"]) else f" [{c['ci_low']:+.3g}, {c['ci_high']:+.3g}]"
            body.append([r["method"], f"{r['rmse_x']:.4g}", f"{r['rmse_y']:.4g}", f"{r['lve']:.4g}",
                         f"{c['mean_diff']:+.3g}{ci}", f"{c['wins']}/{c['n']}", f"{c['p_sign']:.2g}"])
        return head, body

    def format(self) -> str:
        """All tables as aligned text."""
        out = self._header()
        for p in self.protocols():
            head, body = self._table(p)
            w = [max(len(h), *(len(b[i]) for b in body)) for i, h in enumerate(head)]
            fmt = lambda row: "  ".join(s.rjust(w[i]) if i else s.ljust(w[i]) for i, s in enumerate(row))  # noqa: E731
            out += ["", f"protocol {p!r}", fmt(head), fmt(["-" * x for x in w])] + [fmt(b) for b in body]
            out += [f"verdict X: {self.verdict(p, 'rmse_x')}", f"verdict Y: {self.verdict(p, 'rmse_y')}",
                    f"verdict LVE: {self.verdict(p, 'lve')}"]
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
                    f"- LVE: {self.verdict(p, 'lve')}", ""]
        if self.inverse_rows:
            nc = min(6, len(self.inverse_rows[0]["r2"]))
            out += [f"{h}# Inverse maps (held-out frames' X from their own F^y)", "",
                    "| map | RMSE X | LVE | " + " | ".join(f"R² X{j + 1}" for j in range(nc)) + " |",
                    "|---|---|---|" + "---|" * nc]
            out += [f"| {r['map']} | {r['rmse_x']:.4g} | {r['lve']:.4g} | " + " | ".join(f"{x:.3f}" for x in r["r2"][:nc])
                    + " |" for r in self.inverse_rows]
            out.append("")
        return "\n".join(out)
