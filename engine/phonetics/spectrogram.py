"""The sound of an utterance as a phonetician reads it: waveform envelope and a Praat-style spectrogram.

:func:`spectrogram` computes a short-time power spectrum the way Praat's
``Sound: To Spectrogram`` does for its wide-band default look: a Gaussian window
whose *effective* length is ``window_length`` (5 ms: the physical window is twice
that, its ends at exp(-12)), frames every ``time_step`` (2 ms), frequency bins no
finer than Praat's own limit (one eighth of the window's effective bandwidth, about
44 Hz for 5 ms), up to ``max_frequency`` (8 kHz, or the Nyquist frequency below it),
power spectral density in dB re (2e-5 Pa)^2/Hz. :meth:`Spectrogram.grey` paints it as
Praat's ``Spectrogram: Paint`` does by default: +6 dB/octave pre-emphasis about
1 kHz, the loudest cell black, everything 50 dB (the dynamic range) or more below it
white, linear grey between.

:func:`waveform_envelope` reduces samples to (min, max) per bin, what a waveform
display draws when a pixel covers many samples. :func:`read_sound` reads the WAV files
utterances name (any PCM or float WAV, channels averaged). Nothing here draws: the
trajectory editor (:mod:`app.views.sound_panel`) paints these arrays.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from engine.progress import ProgressFn, report

__all__ = ["Spectrogram", "SoundDisplay", "spectrogram", "waveform_envelope", "read_sound", "sound_display",
           "PRAAT_WIDEBAND"]

#: Praat's wide-band spectrogram settings as the trajectory editor shows them
PRAAT_WIDEBAND = {"window_length": 0.005, "max_frequency": 8000.0, "time_step": 0.002,
                  "dynamic_range": 50.0, "preemphasis": 6.0}
#: reference of the dB scale: (2e-5 Pa)^2, as Praat's
_REFERENCE = 4e-10
#: Praat's cap on time and frequency oversampling of the effective window
_OVERSAMPLING = 8
#: frames per block of the short-time transform (memory stays at a few MB whatever the length)
_BLOCK = 2048


@dataclass(frozen=True)
class Spectrogram:
    """Short-time power spectrum of a sound.

    Attributes
    ----------
    times : ndarray of shape (T,), float64
        Centre of each analysis frame, seconds from the start of the sound.
    frequencies : ndarray of shape (F,), float64
        Centre of each bin, Hz, from 0 up.
    power_db : ndarray of shape (F, T), float32
        Power spectral density, dB re (2e-5 Pa)^2/Hz (samples taken as pascals, as
        Praat does); row 0 is the lowest frequency.
    time_step : float
        Seconds between frames.
    window_length : float
        Effective (Gaussian) window length, seconds.
    frequency_step : float
        Hz between band centres (each band is this wide).
    max_frequency : float
        Top of the analysed range, Hz (the bands end at or just below it).
    """

    times: np.ndarray
    frequencies: np.ndarray
    power_db: np.ndarray
    time_step: float
    window_length: float
    frequency_step: float
    max_frequency: float

    def grey(self, *, dynamic_range: float = PRAAT_WIDEBAND["dynamic_range"],
             preemphasis: float = PRAAT_WIDEBAND["preemphasis"], maximum: float | None = None) -> np.ndarray:
        """Grey levels as Praat paints them: 0 = black (loudest), 255 = white.

        Parameters
        ----------
        dynamic_range : float, default=50
            dB below the maximum that are still painted; anything lower is white.
        preemphasis : float, default=6
            dB per octave added about 1 kHz before painting (lifts the weak high
            frequencies of speech, as Praat's default does).
        maximum : float, optional
            The level painted black, dB after pre-emphasis; default the largest value
            (Praat's autoscaling).

        Returns
        -------
        ndarray of shape (F, T), uint8
        """
        if not dynamic_range > 0:
            raise ValueError(f"dynamic_range must be > 0 dB, got {dynamic_range!r}; Praat's default is 50")
        f = np.maximum(self.frequencies, 1e-3 * max(float(self.frequencies[-1]), 1.0))  # no log of 0 Hz
        lift = (preemphasis / math.log(2.0)) * np.log(f / 1000.0)
        db = self.power_db + lift[:, None].astype(np.float32)  # one working copy, changed in place below
        if maximum is not None:
            top = float(maximum)
        else:
            top = float(np.max(db)) if db.size else 0.0
        np.subtract(np.float32(top), db, out=db)
        db *= np.float32(255.0 / dynamic_range)
        np.clip(db, 0.0, 255.0, out=db)
        return np.rint(db, out=db).astype(np.uint8)


@dataclass(frozen=True)
class SoundDisplay:
    """What the editor draws of one sound file: samples, their envelope and the spectrogram.

    Attributes
    ----------
    samples : ndarray of shape (n,), float32
        Mono samples, full scale = 1.
    sample_rate : float
    spectrogram : Spectrogram
    source : str
        The file read.
    """

    samples: np.ndarray
    sample_rate: float
    spectrogram: Spectrogram
    source: str = ""

    @property
    def duration(self) -> float:
        return len(self.samples) / self.sample_rate


def _gaussian_window(n: int, span: float) -> np.ndarray:
    """Praat's Gaussian window: ``n`` samples of a Gaussian ``span`` samples wide, exp(-12) at the
    ends of the span, rescaled to 0 there."""
    i = np.arange(1, n + 1, dtype=np.float64)
    phase = (i - 0.5 * (n + 1)) / span  # -0.5 .. 0.5
    edge = math.exp(-12.0)
    return ((np.exp(-48.0 * phase * phase) - edge) / (1.0 - edge)).astype(np.float32)


def spectrogram(samples, sample_rate, *, window_length: float = PRAAT_WIDEBAND["window_length"],
                max_frequency: float = PRAAT_WIDEBAND["max_frequency"],
                time_step: float = PRAAT_WIDEBAND["time_step"], frequency_step: float = 20.0,
                progress: ProgressFn = None) -> Spectrogram:
    """Short-time power spectrum with Praat's Gaussian window (see the module docstring).

    Parameters
    ----------
    samples : array of shape (n,)
        Mono samples.
    sample_rate : float
        Hz.
    window_length : float, default=0.005
        Effective window length in seconds (0.005: wide band, formants and bursts; 0.03:
        narrow band, harmonics). The Gaussian spans twice this.
    max_frequency : float, default=8000
        Highest frequency kept, Hz (the Nyquist frequency when higher, or <= 0).
    time_step : float, default=0.002
        Seconds between frames (no finer than one eighth of the effective window's time
        width, Praat's limit).
    frequency_step : float, default=20
        Finest bin spacing asked for, Hz (no finer than Praat's limit, one eighth of
        the effective bandwidth).
    progress : callable, optional
        ``progress("spectrogram", done, total)`` per block of frames; raising in it
        (:class:`engine.progress.Cancelled`) stops the computation.

    Returns
    -------
    Spectrogram
        Frames are centred in the sound as Praat centres them; a sound shorter than
        the physical window gives a spectrogram of no frames. The values are Praat's
        (``To Spectrogram`` with the Gaussian window, then ``To Matrix``) in dB.
    """
    from scipy import fft as sfft

    x = np.asarray(samples, dtype=np.float32).reshape(-1)
    sr = float(sample_rate)
    if not (math.isfinite(sr) and sr > 0):
        raise ValueError(f"sample_rate must be a positive number of Hz, got {sample_rate!r}")
    if not (math.isfinite(window_length) and window_length > 0):
        raise ValueError(f"window_length must be > 0 s, got {window_length!r}; 0.005 is Praat's wide band")
    if not (math.isfinite(time_step) and time_step > 0):
        raise ValueError(f"time_step must be > 0 s, got {time_step!r}")
    if not np.isfinite(x).all():
        raise ValueError(f"the sound holds NaN or infinite samples (first at sample "
                         f"{int(np.flatnonzero(~np.isfinite(x))[0])})")
    # Praat's Sound_to_Spectrogram, step by step: the same frames, window, bands and scale
    eff_time = window_length / math.sqrt(math.pi)
    dt = max(float(time_step), eff_time / _OVERSAMPLING)
    f_step = max(float(frequency_step), (1.0 / eff_time) / _OVERSAMPLING)
    nyquist = 0.5 * sr
    f_max = nyquist if not 0 < max_frequency <= nyquist else float(max_frequency)
    physical = 2.0 * window_length  # the Gaussian spans twice the effective length
    half = int(math.floor(physical * sr)) // 2 - 1
    n_win = 2 * half
    if n_win < 2:
        raise ValueError(f"window_length {window_length:g} s holds fewer than 2 samples at {sr:g} Hz; "
                         "give a longer window")
    n_bands = int(math.floor(f_max / f_step))
    if n_bands < 1:
        raise ValueError(f"max_frequency {max_frequency:g} Hz is below one frequency step ({f_step:.3g} Hz)")
    n_fft = 1
    while n_fft < n_win or n_fft < 2 * n_bands * (nyquist / f_max):
        n_fft *= 2
    bin_hz = sr / n_fft
    per_band = max(1, int(math.floor(f_step / bin_hz)))  # FFT bins summed into one band
    f_step = per_band * bin_hz
    n_bands = min(int(math.floor(f_max / f_step)), (n_fft // 2 + 1) // per_band)
    freqs = 0.5 * (f_step - bin_hz) + f_step * np.arange(n_bands)

    dx = 1.0 / sr
    x1 = 0.5 * dx  # sample k (0-based) sits at (k + 0.5) / sr
    duration = len(x) * dx
    n_frames = 1 + int(math.floor((duration - physical) / dt)) if duration >= physical else 0
    t1 = x1 + 0.5 * ((len(x) - 1) * dx - (n_frames - 1) * dt)  # frames centred in the sound
    times = t1 + np.arange(n_frames) * dt
    win = _gaussian_window(n_win, physical * sr)
    # Praat's scale: band power / (sum of the squared window * bins per band), relative to (2e-5 Pa)^2
    scale = np.float32(1.0 / (float(np.sum(win.astype(np.float64) ** 2)) * per_band * _REFERENCE))
    out = np.empty((n_bands, n_frames), dtype=np.float32)
    # a frame starts half a window before the sample at or left of its centre (Praat's arithmetic)
    starts = np.floor((times - x1) / dx).astype(np.int64) + 1 - half
    np.clip(starts, 0, max(len(x) - n_win, 0), out=starts)
    windows = np.lib.stride_tricks.sliding_window_view(x, n_win) if n_frames else None  # a view, no copy
    n_used = n_bands * per_band
    n_blocks = (n_frames + _BLOCK - 1) // _BLOCK
    for b in range(n_blocks):
        report(progress, "spectrogram", b, n_blocks)
        sl = slice(b * _BLOCK, min(n_frames, (b + 1) * _BLOCK))
        assert windows is not None  # n_frames > 0 here
        frames = windows[starts[sl]]  # (B, n_win), a copy of just these frames
        frames *= win
        spec = sfft.rfft(frames, n=n_fft, axis=1, overwrite_x=True)[:, :n_used]
        p = np.square(spec.real)
        p += np.square(spec.imag)
        if per_band > 1:
            p = p.reshape(len(p), n_bands, per_band).sum(axis=2)
        p *= scale
        np.maximum(p, np.float32(1e-30), out=p)
        np.log10(p, out=p)
        p *= np.float32(10.0)
        out[:, sl] = p.T
    report(progress, "spectrogram", n_blocks, n_blocks)
    return Spectrogram(times=times, frequencies=freqs, power_db=out, time_step=dt, window_length=float(window_length),
                       frequency_step=float(f_step), max_frequency=float(f_max))


def waveform_envelope(samples, edges) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) of the samples between successive sample indices ``edges``.

    Parameters
    ----------
    samples : array of shape (n,)
    edges : int array of shape (m + 1,)
        Increasing sample indices (clipped to ``[0, n]``); bin j is ``[edges[j], edges[j+1])``.

    Returns
    -------
    lo, hi : ndarray of shape (m,), float32
        An empty bin takes the sample at its start (so a zoomed-in waveform stays a line).
    """
    x = np.asarray(samples, dtype=np.float32).reshape(-1)
    e = np.clip(np.asarray(edges, dtype=np.int64), 0, len(x))
    if len(e) < 2 or len(x) == 0:
        return np.zeros(max(len(e) - 1, 0), np.float32), np.zeros(max(len(e) - 1, 0), np.float32)
    if np.any(np.diff(e) < 0):
        raise ValueError("edges must be increasing sample indices")
    start = np.minimum(e[:-1], len(x) - 1)
    empty = e[1:] <= e[:-1]
    lo = np.minimum.reduceat(x, start)
    hi = np.maximum.reduceat(x, start)
    lo[empty] = hi[empty] = x[start[empty]]
    return lo.astype(np.float32), hi.astype(np.float32)


def read_sound(path) -> tuple[np.ndarray, float]:
    """(mono samples float32 at full scale 1, sample rate) of a WAV file.

    8/16/24/32-bit PCM and 32/64-bit float WAV files are read; several channels are
    averaged. Raises ValueError naming the file when it is not a WAV file it can read.
    """
    import scipy.io.wavfile

    # no warnings.catch_warnings here: this runs in worker threads, and that context
    # manager swaps process-wide state (app.workers)
    try:
        sr, data = scipy.io.wavfile.read(str(path), mmap=False)
    except (ValueError, EOFError) as exc:
        raise ValueError(f"{path}: not a WAV file this program can read ({exc}); expected PCM or float WAV") from None
    x = np.asarray(data)
    if x.dtype.kind == "u":  # 8-bit WAV is unsigned, centred on 128
        x = (x.astype(np.float32) - 128.0) / 128.0
    elif x.dtype.kind == "i":
        x = x.astype(np.float32) / float(2 ** (8 * x.dtype.itemsize - 1))
    else:
        x = x.astype(np.float32)
    if x.ndim == 2:
        x = x.mean(axis=1, dtype=np.float32)
    if not sr > 0:
        raise ValueError(f"{path}: the WAV header gives a sample rate of {sr} Hz")
    return np.ascontiguousarray(x), float(sr)


def sound_display(path, *, progress: ProgressFn = None, **params) -> SoundDisplay:
    """Read a sound file and compute what the editor shows of it (``params``: :func:`spectrogram`'s)."""
    x, sr = read_sound(path)
    report(progress, "spectrogram", 0, 1)
    spec = spectrogram(x, sr, progress=progress, **{**{k: v for k, v in PRAAT_WIDEBAND.items()
                                                       if k in ("window_length", "max_frequency", "time_step")},
                                                    **params})
    return SoundDisplay(samples=x, sample_rate=sr, spectrogram=spec, source=str(path))
