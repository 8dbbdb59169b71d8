"""Editing the timeline's interval tiers, phones and words, and writing them as a TextGrid (Qt-free).

A boundary is where one interval of a tier ends and the next begins. Moving one keeps
every interval at least one frame long and every key target inside its phone (the
boundary stops at the target, as a phone's mid-point target stays its phone's); a word
boundary and a phone boundary at the same time move together, so the word tier stays
aligned with its phones. Times move on the frame grid of the targets. Every edit returns
new tiers (targets and words are immutable), so the editor keeps the ones before and after
each edit for undo.
"""
from __future__ import annotations

import re
from dataclasses import replace

import numpy as np

__all__ = ["boundaries", "boundary_limits", "move_boundary", "text_words", "write_tiers_textgrid", "TIERS"]

#: the tiers the timeline edits
TIERS = ("phones", "words")
#: two boundaries closer than this (s) are one (a word's edge on its phone's)
_SAME = 1e-6


def boundaries(intervals) -> list[tuple[int, float]]:
    """``(k, time)`` of every inner boundary of a tier: interval k starts where interval k - 1 ends."""
    out = []
    for k in range(1, len(intervals)):
        if abs(float(intervals[k].start) - float(intervals[k - 1].end)) <= _SAME:
            out.append((k, float(intervals[k].start)))
    return out


def _tier(targets, words, tier):
    if tier not in TIERS:
        raise ValueError(f"tier must be one of {TIERS}, got {tier!r}")
    return tuple(targets.phones) if tier == "phones" else tuple(words or ())


def _partner(intervals, t) -> int | None:
    """The boundary index of ``intervals`` at time ``t`` (None: none there)."""
    for k, bt in boundaries(intervals):
        if abs(bt - t) <= _SAME:
            return k
    return None


def _phone_limits(targets, k) -> tuple[float, float]:
    """Where boundary k of the phones may go: one frame into each neighbour, and short of their targets."""
    rate, ph = float(targets.rate), targets.phones
    lo = float(ph[k - 1].start) + 1.0 / rate
    hi = float(ph[k].end) - 1.0 / rate
    a0, a1 = float(ph[k - 1].start) * rate, float(ph[k - 1].end) * rate
    b1 = float(ph[k].end) * rate
    for t in targets.targets:
        f = float(t.frame)
        if a0 - 0.5 <= f < a1 - 0.5:       # in phone k - 1: the boundary stays after it
            lo = max(lo, (f + 1.0) / rate)
        elif a1 - 0.5 <= f < b1 - 0.5:     # in phone k: the boundary stays at or before it
            hi = min(hi, f / rate)
    return lo, hi


def boundary_limits(targets, words, tier: str, k: int) -> tuple[float, float]:
    """The times (s) boundary ``k`` of ``tier`` may move to, inclusive (its own time always inside)."""
    ivs = _tier(targets, words, tier)
    found = dict(boundaries(ivs))
    if k not in found:
        raise IndexError(f"{tier} boundary {k}: the tier has inner boundaries {sorted(found)}")
    t = found[k]
    rate = float(targets.rate)
    lo, hi = float(ivs[k - 1].start) + 1.0 / rate, float(ivs[k].end) - 1.0 / rate
    if tier == "phones":
        lo, hi = _phone_limits(targets, k)
        w = _partner(tuple(words or ()), t)
        if w is not None:
            lo, hi = max(lo, float(words[w - 1].start) + 1.0 / rate), min(hi, float(words[w].end) - 1.0 / rate)
    else:
        p = _partner(tuple(targets.phones), t)
        if p is not None:
            plo, phi = _phone_limits(targets, p)
            lo, hi = max(lo, plo), min(hi, phi)
    return min(lo, t), max(hi, t)


def _moved(intervals, k, t):
    ivs = list(intervals)
    ivs[k - 1] = replace(ivs[k - 1], end=t)
    ivs[k] = replace(ivs[k], start=t)
    return tuple(ivs)


def move_boundary(targets, words, tier: str, k: int, time_s: float):
    """``(targets, words)`` with boundary ``k`` of ``tier`` moved to ``time_s`` (on the frame grid, within
    :func:`boundary_limits`); a boundary of the other tier at the same time moves with it."""
    ivs = _tier(targets, words, tier)
    old = dict(boundaries(ivs))[k] if k in dict(boundaries(ivs)) else None
    lo, hi = boundary_limits(targets, words, tier, k)
    rate = float(targets.rate)
    t = float(np.clip(round(float(time_s) * rate) / rate, lo, hi))
    words = tuple(words or ())
    phones = tuple(targets.phones)
    if tier == "phones":
        w = _partner(words, old)
        phones = _moved(phones, k, t)
        if w is not None:
            words = _moved(words, w, t)
    else:
        p = _partner(phones, old)
        words = _moved(words, k, t)
        if p is not None:
            phones = _moved(phones, p, t)
    return replace(targets, phones=phones), words


#: a word of typed text, as the pronunciation reads it: a bracketed phone string, or letters with apostrophes
_WORD = re.compile(r"\[[^\]]*\]|[^\W\d_](?:[^\W\d_]|')*")


def text_words(text: str, phones) -> tuple:
    """The word tier of typed ``text`` over its phones (``targets_from_text``'s): each word spans the phones
    :func:`engine.phonetics.phones.pronounce` gives it, pauses left out. () when they do not add up."""
    from engine.phonetics.phones import PAUSE, pronounce
    from engine.recordings.corpus import PhoneInterval

    spoken = [p for p in phones if p.label != PAUSE]
    out, i = [], 0
    for word in _WORD.findall(str(text)):
        try:
            n = len(pronounce(word))
        except ValueError:
            return ()
        if n == 0 or i + n > len(spoken):
            return ()
        out.append(PhoneInterval(float(spoken[i].start), float(spoken[i + n - 1].end), word.strip("[]")))
        i += n
    return tuple(out) if i == len(spoken) else ()


def write_tiers_textgrid(path, targets, words=()):
    """Write the timeline's tiers as a Praat TextGrid: ``phones`` (and ``words`` where there is a word
    tier) as interval tiers, the key ``targets`` as a point tier, over the targets' span."""
    from engine.io.writers.praat import IntervalTier, PointTier, write_textgrid

    rate = float(targets.rate)
    xmax = max(float(targets.n_frames) / rate, max([float(p.end) for p in targets.phones], default=0.0))
    tiers = []
    if words:
        tiers.append(IntervalTier("words", [(w.start, w.end, w.label) for w in words]))
    tiers.append(IntervalTier("phones", [(p.start, p.end, p.label) for p in targets.phones]))
    tiers.append(PointTier("targets", [(t.frame / rate, t.label or f"state {t.state}") for t in targets.targets]))
    return write_textgrid(path, 0.0, xmax, tiers)
