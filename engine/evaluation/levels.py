"""A held-out evaluation's errors per level of a metadata field (``lipspace evaluate --by emotion``).

The protocols score every held-out utterance (:class:`engine.evaluation.protocol_report.ProtocolResult`);
here the utterances are grouped by their level of a field (speaker, sex, emotion ...;
:mod:`engine.recordings.metadata`) and each group's errors pooled as the tables pool them
(RMS over all its frames, LVE averaged over its frames). Utterances lacking the field form
the level ``(missing)``. A level with one held-out utterance is shown, and counted, as one:
its figure describes that utterance, not the level.
"""
from __future__ import annotations

from engine.evaluation.protocol_report import _pooled

__all__ = ["per_level", "format_levels", "LEVEL_COLUMNS", "MISSING_LEVEL"]

#: columns of :func:`per_level`'s rows (``field`` and ``level`` first)
LEVEL_COLUMNS = ("field", "level", "protocol", "method", "utterances", "frames", "rmse_x", "rmse_y", "lve", "vel")
#: the level of utterances that lack the field
MISSING_LEVEL = "(missing)"


def per_level(result, levels: dict, *, field: str) -> list[dict]:
    """Pooled errors per protocol, method and level.

    Parameters
    ----------
    result : ProtocolResult
    levels : dict of str to str
        Each utterance id's level ("" = missing).
    field : str
        The field's name (the rows' ``field``).

    Returns
    -------
    list of dict
        :data:`LEVEL_COLUMNS`, in protocol, method, level order.
    """
    groups: dict[tuple, list] = {}
    for p in result._sums:
        lv = levels.get(p["utterance"], "") or MISSING_LEVEL
        groups.setdefault((p["protocol"], p["method"], lv), []).append(p)
    rows = []
    for (proto, method, lv), ps in groups.items():
        pooled = _pooled(ps)
        rows.append({"field": field, "level": lv, "protocol": proto, "method": method, "utterances": len(ps),
                     **{k: pooled[k] for k in ("frames", "rmse_x", "rmse_y", "lve", "vel")}})
    order = {k: i for i, k in enumerate(dict.fromkeys((r["protocol"], r["method"]) for r in result.rows))}
    rows.sort(key=lambda r: (order.get((r["protocol"], r["method"]), len(order)), r["level"] == MISSING_LEVEL,
                             r["level"]))
    return rows


def format_levels(rows, *, field: str) -> str:
    """The rows of :func:`per_level` as an aligned text table per protocol (levels as columns of RMSE X / LVE)."""
    if not rows:
        return f"per {field}: no held-out utterance was scored"
    out = [f"per level of {field!r} (held-out utterances pooled per level: RMSE X / LVE; n = utterances)"]
    for proto in dict.fromkeys(r["protocol"] for r in rows):
        rs = [r for r in rows if r["protocol"] == proto]
        lvls = list(dict.fromkeys(r["level"] for r in rs))
        n = {lv: max(r["utterances"] for r in rs if r["level"] == lv) for lv in lvls}
        head = ["method"] + [f"{lv} (n={n[lv]})" for lv in lvls]
        body = []
        for m in dict.fromkeys(r["method"] for r in rs):
            cells = {r["level"]: f"{r['rmse_x']:.4g} / {r['lve']:.4g}" for r in rs if r["method"] == m}
            body.append([m] + [cells.get(lv, "-") for lv in lvls])
        w = [max(len(h), *(len(b[i]) for b in body)) for i, h in enumerate(head)]
        out += ["", f"protocol {proto!r}", "  ".join(h.ljust(w[i]) if i == 0 else h.rjust(w[i])
                                                    for i, h in enumerate(head))]
        out += ["  ".join(c.ljust(w[i]) if i == 0 else c.rjust(w[i]) for i, c in enumerate(b)) for b in body]
    single = sorted({r["level"] for r in rows if r["utterances"] == 1})
    if single:
        out.append(f"levels with one held-out utterance ({', '.join(single[:6])}): their figures describe that "
                   "utterance, not the level")
    return "\n".join(out)
