"""Editing the trajectory editor's key targets, and its time axis (Qt-free).

Every edit returns a new :class:`engine.phonetics.targets.TargetSequence` (they are immutable),
so the editor keeps the one before and after each edit for undo / redo.

A target belongs to the phone interval it lies in (a phone mid-point target to its
phone): dragging it keeps it inside that interval and strictly between its
neighbours, so a target never changes phone by being moved. A target that lies in no
phone interval (a clicked state placed after the last phone) is kept between its
neighbours and inside the trajectory.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

__all__ = ["phone_frames", "target_bounds", "move_target", "remove_target", "time_ticks", "TICK_STEPS_MS"]

#: tick spacings offered on the time axis, in milliseconds
TICK_STEPS_MS = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000, 20000, 60000)


def phone_frames(phone, rate: float, n_frames: int) -> tuple[int, int]:
    """First and last frame (inclusive) of a phone interval at ``rate`` Hz, within 0..n_frames-1."""
    lo = int(round(float(phone.start) * rate))
    hi = int(round(float(phone.end) * rate)) - 1
    lo = min(max(lo, 0), n_frames - 1)
    return lo, min(max(hi, lo), n_frames - 1)


def _phone_of(targets, index: int):
    """(lo, hi) of the phone interval target ``index`` lies in (its own label first), or None."""
    t = targets.targets[index]
    best = None
    for p in targets.phones:
        lo, hi = phone_frames(p, targets.rate, targets.n_frames)
        if lo <= t.frame <= hi:
            if p.label == t.label:
                return lo, hi
            best = best or (lo, hi)
    return best


def target_bounds(targets, index: int) -> tuple[int, int]:
    """The frames target ``index`` may move to: inside its phone interval and between its neighbours.

    Returns
    -------
    (lo, hi) : tuple of int
        Inclusive; ``lo <= frame <= hi`` always holds for the target's own frame.
    """
    ts = targets.targets
    if not 0 <= index < len(ts):
        raise IndexError(f"target {index} out of range 0..{len(ts) - 1}")
    lo = ts[index - 1].frame + 1 if index > 0 else 0
    hi = ts[index + 1].frame - 1 if index + 1 < len(ts) else targets.n_frames - 1
    phone = _phone_of(targets, index)
    if phone is not None:
        lo, hi = max(lo, phone[0]), min(hi, phone[1])
    f = ts[index].frame
    return min(lo, f), max(hi, f)


def move_target(targets, index: int, frame: int):
    """A copy of ``targets`` with target ``index`` moved to ``frame``, clamped to :func:`target_bounds`."""
    lo, hi = target_bounds(targets, index)
    ts = list(targets.targets)
    ts[index] = replace(ts[index], frame=int(np.clip(int(frame), lo, hi)))
    return replace(targets, targets=tuple(ts))


def remove_target(targets, index: int):
    """A copy of ``targets`` without target ``index``; ValueError for the last one left."""
    ts = list(targets.targets)
    if not 0 <= index < len(ts):
        raise IndexError(f"target {index} out of range 0..{len(ts) - 1}")
    if len(ts) == 1:
        raise ValueError("the last target cannot be removed: synthesis needs at least one")
    del ts[index]
    return replace(targets, targets=tuple(ts))


def time_ticks(t0_ms: float, t1_ms: float, width_px: float, min_spacing_px: float = 56.0) -> tuple[int, list[int]]:
    """Tick marks of a time axis from ``t0_ms`` to ``t1_ms`` drawn ``width_px`` pixels wide.

    Returns
    -------
    step_ms : int
        The smallest of :data:`TICK_STEPS_MS` whose ticks are at least ``min_spacing_px``
        apart (the largest when none is).
    ticks_ms : list of int
        Multiples of ``step_ms`` in ``[t0_ms, t1_ms]``.
    """
    span = float(t1_ms) - float(t0_ms)
    if not span > 0 or not width_px > 0:
        return TICK_STEPS_MS[-1], []
    px_per_ms = float(width_px) / span
    step = next((s for s in TICK_STEPS_MS if s * px_per_ms >= min_spacing_px), TICK_STEPS_MS[-1])
    first = int(np.ceil(float(t0_ms) / step)) * step
    return step, list(range(first, int(np.floor(float(t1_ms))) + 1, step))
