"""The summary tables of docs/RESULTS.md, from the protocol results of each corpus.

A summary *cell* says, for one corpus and protocol, which method has the lowest pooled
error and by how much, always as Δ = manifold − other (negative: the manifold method
erred less): against the runner-up when the manifold method wins, against the winner
when another method does -- the mean per-utterance difference with its 95 % bootstrap
interval, the relative difference of the pooled errors, on how many utterances the
winner wins, and the paired tests; a corpus with one test utterance pairs the gaps between
its targets instead (X and LVE). A manifold method that equals another exactly (no
validation split: it is then a spline through the targets) is a tie, not a win.
The cells are computed when a corpus is run and cached with its section, so the
summary can be assembled from sections computed at different times.
"""
from __future__ import annotations

import numpy as np

REFERENCE = "manifold"
#: methods a winner or runner-up is picked from (the mean frame is a floor, not a contender)
_FLOOR = "mean-frame"


def _delta(c) -> str:
    """Δ = reference − baseline of a paired comparison (negative: the reference erred less), with its interval."""
    if not np.isfinite(c["ci_low"]):
        return f"{0.0 - c['mean_diff']:+.3g} (one utterance)"
    return f"{-c['mean_diff']:+.3g} [{-c['ci_high']:+.3g}, {-c['ci_low']:+.3g}]" + _over(c)


def _over(c) -> str:
    """What a comparison paired: nothing said for utterances, the gaps of one utterance said."""
    return f" over {c['n']} gaps of one utterance" if c.get("unit") == "gaps" else ""


def summary_cells(result, measure="rmse_x") -> dict:
    """protocol -> a JSON-able summary of who wins ``measure`` and by how much (Δ = manifold − other)."""
    out = {}
    for p in result.protocols():
        rows = [r for r in result.rows if r["protocol"] == p and r["method"] != _FLOOR]
        rows.sort(key=lambda r: r[measure])
        winner = rows[0]["method"]
        ref = result.row(p, REFERENCE)[measure]
        other = rows[1]["method"] if winner == REFERENCE else winner
        c = result.comparison(p, other, measure)  # other - manifold per utterance
        o = result.row(p, other)[measure]
        tie = c["wins"] == 0 and c["losses"] == 0
        out[p] = {"winner": "tie" if tie else winner, "other": other, "delta": -c["mean_diff"],
                  "ci_low": -c["ci_high"], "ci_high": -c["ci_low"], "n": c["n"],
                  "winner_wins": c["wins"] if winner == REFERENCE else c["losses"], "p_sign": c["p_sign"],
                  "p_wilcoxon": c["p_wilcoxon"], "percent": 100 * (ref - o) / o, "unit": c.get("unit", "utterances")}
    return out


def format_cell(cell) -> str:
    if cell is None:
        return "— (no phone labels)"
    if cell["winner"] == "tie":
        return f"tie: manifold = {cell['other']} (identical trajectories)"
    if np.isfinite(cell["ci_low"]):
        d = f"Δ {cell['delta']:+.3g} [{cell['ci_low']:+.3g}, {cell['ci_high']:+.3g}]" + _over(cell)
        tests = f"; p {cell['p_sign']:.2g} sign / {cell['p_wilcoxon']:.2g} signed-rank"
    else:
        d, tests = f"Δ {cell['delta']:+.3g} (one utterance)", ""
    who = f"vs {cell['other']}" if cell["winner"] == REFERENCE else "manifold vs it"
    unit = " gaps" if cell.get("unit") == "gaps" else ""
    return (f"**{cell['winner']}**: {who} {d}, {cell['percent']:+.1f} %; wins {cell['winner_wins']}/{cell['n']}"
            + unit + tests)


def summary_table(entries, protocols, measure_label) -> list[str]:
    """Markdown rows: one per (name, cells) entry, one column per protocol."""
    lines = [f"| corpus ({measure_label}) | " + " | ".join(f"`{p}`" for p in protocols) + " |",
             "|---|" + "---|" * len(protocols)]
    for name, cells in entries:
        lines.append(f"| {name} | " + " | ".join(format_cell(cells.get(p)) for p in protocols) + " |")
    return lines


def contribution_cells(result) -> dict:
    """protocol -> the two gains that are the manifold's: the states' velocities (state-velocity Hermite
    against the better of linear and PCHIP) and the learnt paths (manifold against state-velocity Hermite),
    each as a mean per-utterance difference in RMSE X with interval and wins."""
    from engine.evaluation.paired import paired_comparison

    out = {}
    for p in result.protocols():
        names = {r["method"] for r in result.rows if r["protocol"] == p}
        if not {"sv-hermite", "linear", "pchip"} <= names:
            continue
        per = {}
        for x in result.per_utterance:
            if x["protocol"] == p:
                per.setdefault(x["method"], {})[x["utterance"]] = x["rmse_x"]
        plain = min(("linear", "pchip"), key=lambda m: result.row(p, m)["rmse_x"])
        uids = sorted(per["sv-hermite"])
        cells = {}
        for key, a, b in (("velocities", "sv-hermite", plain), ("paths", REFERENCE, "sv-hermite")):
            c = paired_comparison([per[a][u] for u in uids], [per[b][u] for u in uids], n_boot=2000).as_dict()
            cells[key] = {"better": a, "than": b, **c}
        out[p] = cells
    return out


def contribution_table(entries) -> list[str]:
    lines = ["| corpus | protocol | state velocities: sv-hermite − (linear or PCHIP) (ΔX [95 % CI], wins) | "
             "learnt paths: manifold − sv-hermite (ΔX [95 % CI], wins) |", "|---|---|---|---|"]
    for name, cells in entries:
        for p, c in cells.items():
            v, w = c["velocities"], c["paths"]
            lines.append(f"| {name} | `{p}` | {_delta(v)} vs {v['than']} ({v['wins']}/{v['n']}) | "
                         f"{_delta(w)} ({w['wins']}/{w['n']}) |")
    return lines
