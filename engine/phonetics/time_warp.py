"""Pitch-keeping time warping (WSOLA) of a sound, through anchors placed exactly.

:func:`time_warp` moves chosen samples of a sound to chosen places (the speech audio puts
each phone's start on the talker's phone start) and stretches linearly between them;
:func:`time_stretch` is the uniform case. Waveform-similarity overlap-add: 23 ms Hann
windows (at 22,050 Hz) every at most 11.6 ms of output, each taken from where the warp
maps its centre and moved by up to ±5.8 ms to continue the previous window's waveform,
so the pitch is kept (plain resampling would shift it by the stretch factor).
"""
from __future__ import annotations

import numpy as np

__all__ = ["time_stretch", "time_warp", "WINDOW"]

#: samples per overlap-add window (23 ms at 22,050 Hz)
WINDOW = 512


def time_stretch(x, n_out: int) -> np.ndarray:
    """Stretch (or compress) ``x`` to ``n_out`` samples keeping its pitch (WSOLA).

    Parameters
    ----------
    x : ndarray of shape (n,) float32
    n_out : int

    Returns
    -------
    ndarray of shape (n_out,) float32
    """
    x = np.asarray(x, np.float32)
    n_out = int(n_out)
    h = WINDOW // 2
    if len(x) < 2 * WINDOW or n_out < 2 * WINDOW:
        return time_warp(x, [0, len(x)], [0, n_out], n_out)
    # frame centres h ... len - h onto h ... n_out - h: the first and last frames are x's own
    return time_warp(x, [h, len(x) - h], [h, n_out - h], n_out)


def time_warp(x, source, target, n_out: int) -> np.ndarray:
    """Warp ``x`` in time so that sample ``source[i]`` comes out at ``target[i]``, keeping the pitch.

    Between anchors time is stretched linearly (and beyond the ends with the nearest
    piece's rate). A window is centred exactly on every target anchor and taken, unmoved,
    from its source anchor, so each anchor lands to the sample; the windows between are
    evenly at most 11.6 ms apart, each moved by up to ±5.8 ms to continue the previous
    one's waveform. No window reads ``x`` at or past the next anchor's source sample, so
    nothing after an anchor is heard before its target (stretching would otherwise
    replay the start of what follows early).

    Parameters
    ----------
    x : ndarray of shape (n,) float32
    source : sequence of float, shape (k,)
        Sample positions in ``x`` (non-decreasing).
    target : sequence of float, shape (k,)
        Where they go in the output (increasing).
    n_out : int

    Returns
    -------
    ndarray of shape (n_out,) float32
    """
    x = np.asarray(x, np.float32)
    src, dst = np.asarray(source, np.float64), np.asarray(target, np.float64)
    if src.shape != dst.shape or src.ndim != 1 or len(src) < 2:
        raise ValueError(f"source and target need the same length, at least 2 anchors; got {src.shape} and {dst.shape}")
    if np.any(np.diff(dst) <= 0) or np.any(np.diff(src) < 0):
        raise ValueError(f"time_warp anchors must increase (target strictly, source never decreasing); got "
                         f"target steps down to {np.diff(dst).min():g}, source steps down to {np.diff(src).min():g}")
    n_out = int(n_out)
    if n_out <= 0:
        return np.zeros(0, np.float32)
    if not len(x):
        return np.zeros(n_out, np.float32)

    def warp(t):  # output sample -> input sample, linear beyond the end anchors
        t = np.asarray(t, np.float64)
        r0 = (src[1] - src[0]) / (dst[1] - dst[0])
        r1 = (src[-1] - src[-2]) / (dst[-1] - dst[-2])
        return np.where(t < dst[0], src[0] + (t - dst[0]) * r0,
                        np.where(t > dst[-1], src[-1] + (t - dst[-1]) * r1, np.interp(t, dst, src)))

    win, tol = WINDOW, WINDOW // 4
    if len(x) < 2 * win or n_out < 2 * win:  # too short to overlap-add: plain resampling through the warp
        return np.interp(np.clip(warp(np.arange(n_out)), 0, len(x) - 1), np.arange(len(x)), x).astype(np.float32)
    centres, fixed = _frame_centres(np.round(dst).astype(np.int64), n_out, win // 2)
    h, edge = win // 2, win + tol
    nominal = np.round(warp(centres)).astype(np.int64) - h  # first input sample of each frame
    nominal = np.clip(nominal, -win, len(x))
    # a frame reads no input at or beyond the next anchor's source sample, so no phone's sound is heard
    # before its start (WSOLA's pre-echo when a frame near a stretched phone's end reaches into the next)
    nxt = np.searchsorted(np.round(dst), centres, side="right")
    limit = np.where(nxt < len(src), np.round(src[np.minimum(nxt, len(src) - 1)]), len(x) + edge).astype(np.int64)
    pad = np.concatenate([np.zeros(edge, np.float32), x, np.zeros(edge, np.float32)])
    w = np.hanning(win + 1)[:win].astype(np.float32)
    ramp = np.arange(win)
    out = np.zeros(n_out + 2 * win, np.float32)   # output sample t at out[t + win]
    norm = np.zeros(n_out + 2 * win, np.float32)
    prev_pos = prev_k = None
    for c, pos, exact, lim in zip(centres, nominal, fixed, limit):
        k = int(c) - h
        pos = int(pos)
        hi = min(pos + tol, int(lim) - win)
        if prev_pos is not None and prev_k is not None and not exact and hi > pos - tol:
            # the input that would continue the previous frame naturally over this output hop
            follow = pad[edge + prev_pos + k - prev_k: edge + prev_pos + k - prev_k + win]
            corr = np.correlate(pad[edge + pos - tol: edge + hi + win], follow, mode="valid")
            pos = pos - tol + int(np.argmax(corr))
        wk = w if pos + win <= lim else w * (pos + ramp < lim)
        out[k + win:k + 2 * win] += wk * pad[edge + pos: edge + pos + win]
        norm[k + win:k + 2 * win] += wk
        prev_pos, prev_k = pos, k
    norm[norm < 1e-3] = 1.0
    return (out / norm)[win:win + n_out]


def _frame_centres(anchors, n_out, h):
    """Output frame centres: one on every anchor (marked True: taken exactly, not searched), and
    between and beyond them evenly at most ``h`` apart, covering ``0 ... n_out``."""
    inside = anchors[(anchors >= 0) & (anchors < n_out)]
    inside = np.unique(inside)
    if not len(inside):
        c = np.arange(0, n_out + h, h)
        return c, np.zeros(len(c), bool)
    parts, marks = [], []
    head = np.arange(inside[0] - h, -h, -h)[::-1]
    parts.append(head)
    marks.append(np.zeros(len(head), bool))
    for a, b in zip(inside[:-1], inside[1:]):
        m = int(np.ceil((b - a) / h))
        parts.append(a + np.round(np.arange(m) * (b - a) / m).astype(np.int64))
        marks.append(np.arange(m) == 0)
    tail = inside[-1] + np.arange(0, n_out + h - inside[-1], h)
    parts.append(tail)
    marks.append(np.arange(len(tail)) == 0)
    return np.concatenate(parts).astype(np.int64), np.concatenate(marks)
