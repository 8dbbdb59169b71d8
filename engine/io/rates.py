"""Changing a corpus's frame rate, per utterance, with an anti-aliasing filter."""
from __future__ import annotations

from dataclasses import replace
from fractions import Fraction
from typing import Any

import numpy as np

from engine.recordings.corpus import Corpus, CorpusError

__all__ = ["resample", "resampled_length", "how"]

#: largest up/down factor used for polyphase resampling; other ratios use filter + interpolation
MAX_FACTOR = 1000


def _ratio(old: float, new: float):
    frac = Fraction(new / old).limit_denominator(MAX_FACTOR)
    if frac.numerator and frac.numerator <= MAX_FACTOR and abs(old * frac - new) <= 1e-9 * new:
        return frac.numerator, frac.denominator
    return None


def resampled_length(n: int, old: float, new: float) -> int:
    """Frames an utterance of ``n`` frames at ``old`` Hz has at ``new`` Hz (covers its duration)."""
    return max(1, int(np.ceil(n * new / old - 1e-9)))


def _resample_block(x: np.ndarray, old: float, new: float) -> np.ndarray:
    """Resample the rows of ``x`` (n, c) from ``old`` to ``new`` Hz; sample k sits at k / new s."""
    from scipy import signal

    n = x.shape[0]
    m = resampled_length(n, old, new)
    x = x.astype(np.float64)
    if n < 2:
        return np.repeat(x[:1], m, axis=0)
    ud = _ratio(old, new)
    if ud is not None:
        up, down = ud
        y = signal.resample_poly(x, up, down, axis=0, padtype="line")
    else:
        if new < old:  # zero-phase low-pass at 0.9 x the new Nyquist, then interpolate
            sos = signal.butter(8, 0.9 * new / old, output="sos")
            pad = min(3 * (2 * sos.shape[0] + 1), n - 1)
            x = signal.sosfiltfilt(sos, x, axis=0, padlen=pad)
        t_old = np.arange(n) / old
        t_new = np.arange(m) / new
        y = np.empty((m, x.shape[1]))
        for j in range(x.shape[1]):
            y[:, j] = np.interp(t_new, t_old, x[:, j])
    if y.shape[0] < m:
        y = np.concatenate([y, np.repeat(y[-1:], m - y.shape[0], axis=0)])
    return y[:m]


def resample(corpus: Corpus, rate: float, *, progress=None) -> Corpus:
    """The corpus at a new frame rate.

    Each utterance is resampled on its own (nothing crosses an utterance bound): for
    rational ratios with factors up to :data:`MAX_FACTOR` by polyphase filtering
    (``scipy.signal.resample_poly``, its Kaiser-windowed anti-aliasing FIR, edges padded
    along a line); otherwise by a zero-phase 8th-order Butterworth low-pass at 0.9 x the
    new Nyquist frequency (when downsampling) and linear interpolation. New frame k sits
    at k / rate s; an utterance of n frames gets ceil(n * rate / old) frames, so it still
    covers its phones. Phone times are unchanged (seconds); a phone end beyond the new
    last frame by more than the corpus tolerance is cut to the utterance's duration.
    Float latent signals are resampled the same way; integer and boolean ones are
    sampled at the nearest old frame.

    Parameters
    ----------
    corpus : Corpus
    rate : float
        New frame rate, Hz.
    progress : callable, optional
        ``progress(stage, done, total)``, called once per utterance.

    Returns
    -------
    Corpus
        A new corpus (the input is untouched); frames float32.
    """
    rate = float(rate)
    if not np.isfinite(rate) or rate <= 0:
        raise CorpusError(f"{corpus.name}: cannot resample to {rate} Hz; expected a positive rate")
    old = corpus.rate
    if abs(rate - old) <= 1e-9 * old:
        return Corpus(frames=corpus.frames.copy(), rate=old, utterances=list(corpus.utterances), dims=corpus.dims,
                      faces=corpus.faces, point_names=corpus.point_names,
                      latent={k: v.copy() for k, v in corpus.latent.items()}, name=corpus.name,
                      point_roles=corpus.point_roles, registration=corpus.registration,
                      history=list(corpus.history), axes=corpus.axes, units=corpus.units)
    lat: dict[str, list[Any]]
    blocks, utts, lat = [], [], {k: [] for k in corpus.latent}
    pos = 0
    total = len(corpus.utterances)
    for i, u in enumerate(corpus.utterances):
        F = corpus.frames[u.start:u.stop]
        y = _resample_block(F, old, rate).astype(np.float32)
        m = y.shape[0]
        blocks.append(y)
        for k, v in corpus.latent.items():
            seg = v[u.start:u.stop]
            if np.issubdtype(seg.dtype, np.floating):
                r = _resample_block(seg.reshape(seg.shape[0], -1), old, rate).reshape((m,) + seg.shape[1:])
                lat[k].append(r.astype(seg.dtype))
            else:
                near = np.clip(np.round(np.arange(m) * old / rate).astype(np.int64), 0, seg.shape[0] - 1)
                lat[k].append(seg[near])
        dur = m / rate
        phones = []
        for p in u.phones:
            if p.start >= dur:
                continue
            end = min(p.end, dur) if p.end > dur + 0.5 / rate else p.end
            if end > p.start:
                phones.append(replace(p, end=end))
        # the recording's own length, which the new frames round up to a whole frame
        utts.append(replace(u, start=pos, stop=pos + m, phones=tuple(phones),
                            duration_s=float(u.duration_s) or F.shape[0] / old))
        pos += m
        if progress is not None:
            progress("resample", i + 1, total)
    frames = np.concatenate(blocks, axis=0)
    if frames.shape[0] < 2:
        raise CorpusError(f"{corpus.name}: resampling to {rate:g} Hz leaves {frames.shape[0]} frame; "
                          "expected at least 2 (choose a higher rate)")
    return Corpus(frames=frames, rate=rate, utterances=utts, dims=corpus.dims, faces=corpus.faces,
                  point_names=corpus.point_names, latent={k: np.concatenate(v) for k, v in lat.items()},
                  name=corpus.name, point_roles=corpus.point_roles, registration=corpus.registration,
                  history=list(corpus.history) + [f"resampled {old:g} -> {rate:g} Hz ({how(old, rate)})"],
                  axes=corpus.axes, units=corpus.units)


def how(old: float, new: float) -> str:
    """The filter :func:`resample` uses between two rates, in words."""
    ud = _ratio(old, new)
    if ud is not None:
        return f"polyphase x{ud[0]}/{ud[1]}, Kaiser-windowed anti-aliasing FIR"
    if new < old:
        return "8th-order zero-phase Butterworth anti-aliasing low-pass at 0.9 x the new Nyquist, linear interpolation"
    return "linear interpolation (upsampling)"
