"""Zero-phase low-pass filtering and velocities of per-frame signals, utterance by utterance.

Articulograph positions carry measurement noise that a derivative amplifies; labs
low-pass them before computing velocities (mview, ema2wav, R ``ag501``). Here a
Butterworth filter of order :data:`DEFAULT_ORDER` runs forwards and backwards
(``scipy.signal.sosfiltfilt``: no phase shift, so landmarks keep their times; the
magnitude response is squared, -6 dB at the cut-off) over each utterance on its own, so
nothing leaks across an utterance boundary. The default cut-off, :data:`DEFAULT_CUTOFF_HZ`,
is chosen in docs/DECISIONS.md; a cut-off at or above the Nyquist frequency is refused.
"""
from __future__ import annotations

import numpy as np

__all__ = ["DEFAULT_CUTOFF_HZ", "DEFAULT_ORDER", "lowpass", "velocity", "check_cutoff"]

#: default low-pass cut-off for lip, jaw and tongue positions (Hz)
DEFAULT_CUTOFF_HZ = 15.0
#: Butterworth order (doubled by the forward-backward pass)
DEFAULT_ORDER = 4


def check_cutoff(cutoff_hz: float, rate: float) -> float:
    """``cutoff_hz`` as a float if it lies in (0, Nyquist); ValueError naming both and the fix otherwise."""
    c = float(cutoff_hz)
    nyq = 0.5 * float(rate)
    if not (np.isfinite(c) and 0 < c < nyq):
        raise ValueError(f"low-pass cut-off {cutoff_hz:g} Hz: must be above 0 and below the Nyquist frequency "
                         f"{nyq:g} Hz of {float(rate):g} Hz frames (give a lower cut-off, or import at a higher "
                         "rate: lipspace import --resample)")
    return c


def lowpass(x, bounds, rate: float, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ, order: int = DEFAULT_ORDER):
    """``x`` low-passed per utterance with a zero-phase Butterworth filter.

    Parameters
    ----------
    x : ndarray of shape (N,) or (N, k)
    bounds : ndarray of shape (U, 2)
        Utterance ranges ``[start, stop)``.
    rate : float
        Frames per second.
    cutoff_hz : float
        -6 dB point of the forward-backward pass, below ``rate / 2``.
    order : int

    Returns
    -------
    ndarray of shape like ``x``, float64
        Utterances of fewer than 3 frames are returned as they are (nothing to filter).
    """
    from scipy.signal import butter, sosfiltfilt

    check_cutoff(cutoff_hz, rate)
    if int(order) < 1:
        raise ValueError(f"filter order {order!r}; expected a positive whole number")
    sos = butter(int(order), cutoff_hz / (0.5 * rate), output="sos")
    x = np.asarray(x, np.float64)
    out = x.copy()
    for a, b in np.asarray(bounds, np.int64).tolist():
        n = b - a
        if n < 3:
            continue
        pad = min(3 * (2 * len(sos) + 1), n - 1)  # scipy's default, shortened for short utterances
        out[a:b] = sosfiltfilt(sos, x[a:b], axis=0, padlen=pad)
    return out


def velocity(x, bounds, rate: float) -> np.ndarray:
    """Time derivative of ``x`` per utterance (central differences, one-sided at the ends), units per second.

    Parameters
    ----------
    x : ndarray of shape (N,) or (N, k)
    bounds : ndarray of shape (U, 2)
    rate : float

    Returns
    -------
    ndarray like ``x``, float64; 0 in an utterance of one frame.
    """
    x = np.asarray(x, np.float64)
    out = np.zeros_like(x)
    for a, b in np.asarray(bounds, np.int64).tolist():
        if b - a >= 2:
            out[a:b] = np.gradient(x[a:b], axis=0) * float(rate)
    return out
