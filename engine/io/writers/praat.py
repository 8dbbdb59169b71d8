"""Praat TextGrids out: interval and point tiers in Praat's long text format, written atomically.

Interval tiers must cover ``[xmin, xmax]`` without gaps in Praat, so the gaps between
the given intervals are filled with empty intervals; labels are written as Praat
writes them (UTF-8, a double quote doubled). The files open in Praat and read back
with :func:`engine.io.read_textgrid` (praat-textgrids).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

from engine.files.atomic import write_text_atomic

__all__ = ["IntervalTier", "PointTier", "textgrid_text", "write_textgrid", "textgrid_names"]


@dataclass(frozen=True)
class IntervalTier:
    """A named tier of labelled intervals ``(start s, end s, label)`` in time order, not overlapping."""

    name: str
    intervals: list


@dataclass(frozen=True)
class PointTier:
    """A named tier of labelled points ``(time s, label)`` in time order."""

    name: str
    points: list


def _num(x: float) -> str:
    return repr(float(x)) if not float(x).is_integer() else str(int(x))


def _quote(text: str) -> str:
    return '"' + str(text).replace('"', '""') + '"'


def _filled(tier: IntervalTier, xmin: float, xmax: float) -> list[tuple[float, float, str]]:
    """The tier's intervals clipped to [xmin, xmax], gaps filled with empty intervals."""
    out, t = [], xmin
    tol = 1e-9 * max(1.0, abs(xmax))
    for k, (s, e, lab) in enumerate(tier.intervals):
        s, e = float(s), float(e)
        if not (math.isfinite(s) and math.isfinite(e)) or e < s:
            raise ValueError(f"tier {tier.name!r} interval {k + 1} ({s!r}-{e!r}): expected finite start <= end")
        if s < t - tol:
            raise ValueError(f"tier {tier.name!r} interval {k + 1} starts at {s:g} s, before the previous one "
                             f"ends at {t:g} s; expected intervals in time order, not overlapping")
        s, e = max(s, xmin), min(e, xmax)
        if e - s <= tol:
            continue
        if s - t > tol:
            out.append((t, s, ""))
        out.append((max(s, t), e, str(lab)))
        t = e
    if xmax - t > tol or not out:
        out.append((t, xmax, ""))
    return out


def textgrid_text(xmin: float, xmax: float, tiers) -> str:
    """The TextGrid (Praat's long text format) of ``tiers`` over ``[xmin, xmax]`` seconds."""
    xmin, xmax = float(xmin), float(xmax)
    if not (math.isfinite(xmin) and math.isfinite(xmax) and xmax > xmin):
        raise ValueError(f"a TextGrid spans xmin < xmax seconds; got {xmin!r} .. {xmax!r}")
    lines = ['File type = "ooTextFile"', 'Object class = "TextGrid"', "", f"xmin = {_num(xmin)} ",
             f"xmax = {_num(xmax)} ", "tiers? <exists> ", f"size = {len(tiers)} ", "item []: "]
    for i, tier in enumerate(tiers, start=1):
        lines.append(f"    item [{i}]:")
        if isinstance(tier, IntervalTier):
            ivs = _filled(tier, xmin, xmax)
            lines += ['        class = "IntervalTier" ', f"        name = {_quote(tier.name)} ",
                      f"        xmin = {_num(xmin)} ", f"        xmax = {_num(xmax)} ",
                      f"        intervals: size = {len(ivs)} "]
            for k, (s, e, lab) in enumerate(ivs, start=1):
                lines += [f"        intervals [{k}]:", f"            xmin = {_num(s)} ",
                          f"            xmax = {_num(e)} ", f"            text = {_quote(lab)} "]
        elif isinstance(tier, PointTier):
            pts = [(float(t), str(lab)) for t, lab in tier.points if xmin <= float(t) <= xmax]
            if any(b[0] < a[0] for a, b in zip(pts, pts[1:])):
                raise ValueError(f"point tier {tier.name!r}: expected points in time order")
            lines += ['        class = "TextTier" ', f"        name = {_quote(tier.name)} ",
                      f"        xmin = {_num(xmin)} ", f"        xmax = {_num(xmax)} ",
                      f"        points: size = {len(pts)} "]
            for k, (t, lab) in enumerate(pts, start=1):
                lines += [f"        points [{k}]:", f"            number = {_num(t)} ",
                          f"            mark = {_quote(lab)} "]
        else:
            raise TypeError(f"tier {i}: expected an IntervalTier or PointTier, got {type(tier).__name__}")
    return "\n".join(lines) + "\n"


def write_textgrid(path, xmin: float, xmax: float, tiers) -> Path:
    """Write ``tiers`` over ``[xmin, xmax]`` as a TextGrid file (atomically)."""
    return write_text_atomic(path, textgrid_text(xmin, xmax, tiers))


def textgrid_names(utterance_ids) -> list[str]:
    """A file name per utterance id: ``<id>.TextGrid`` with characters a file name cannot hold replaced,
    made unique (``_2``, ``_3`` ...) where two ids become one name."""
    out, seen = [], set()
    for uid in utterance_ids:
        stem = re.sub(r'[\x00-\x1f/\\:*?"<>|]', "_", str(uid)).strip(" .") or "utterance"
        name, k = f"{stem}.TextGrid", 2
        while name.lower() in seen:
            name, k = f"{stem}_{k}.TextGrid", k + 1
        seen.add(name.lower())
        out.append(name)
    return out
