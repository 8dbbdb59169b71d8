"""Speech audio for the synthetic talker: espeak-ng, word by word, stretched to the talker's timing.

The talker's utterances carry phone timings but no sound. :func:`add_speech_audio`
gives each utterance a WAV file (22,050 Hz, 16-bit mono) that plays in the explorer
like the audio of a recorded corpus (``Utterance.audio``):

1. espeak-ng (a system package; optional) speaks the sentence once, as SSML with a
   250 ms break between words, so the words come out separated by silence;
2. the words are cut at the longest silences (one fewer than there are words; a
   sentence whose silences cannot be matched to its words is stretched as a whole);
3. each word is time-stretched (WSOLA: overlap-add of 23 ms Hann windows whose
   positions are adjusted by cross-correlation, so the pitch is kept) to exactly the
   span its phones take in the talker's timing, and placed at its first phone's start.

Each word's sound therefore starts at its first phone and ends with its last phone
(to the sample, by construction); inside a word the phones keep espeak-ng's own
relative timing, not the talker's (``info["stretch"]`` of :func:`utterance_audio`
says how far each word was stretched to fit). espeak-ng pronounces from its own lexicon, which
differs from the CMU dictionary the talker uses in a few words.

Without espeak-ng, :func:`espeak_path` is None and :func:`add_speech_audio` raises
:class:`SpeechAudioUnavailable` with one line saying how to install it.
"""
from __future__ import annotations

import dataclasses
import io
import shutil
import subprocess
import wave
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from engine._atomic import write_wav_atomic
from engine.phonetics import PAUSE, pronounce
from engine.progress import report

__all__ = ["SpeechAudioUnavailable", "espeak_path", "word_spans", "time_stretch", "utterance_audio",
           "add_speech_audio", "read_wav", "SAMPLE_RATE"]

SAMPLE_RATE = 22050
_BREAK_MS = 250
_MIN_GAP_S = 0.12
_WIN = 512


class SpeechAudioUnavailable(RuntimeError):
    """espeak-ng is not installed, so the synthetic talker has no audio."""


def espeak_path() -> str | None:
    """Path of the ``espeak-ng`` program, or None when it is not installed."""
    return shutil.which("espeak-ng")


def _require_espeak() -> str:
    exe = espeak_path()
    if exe is None:
        raise SpeechAudioUnavailable("espeak-ng is not installed, so the synthetic talker is silent (Debian/Ubuntu: "
                                     "apt-get install espeak-ng); everything else works without it")
    return exe


def word_spans(utterance) -> list[tuple[str, float, float]]:
    """(word, start s, end s) of each word of a synthetic utterance, from its text and phones.

    The words' CMU pronunciations are matched in order to the utterance's non-pause phones.

    Raises
    ------
    ValueError
        When the phones do not spell the text's words (not a synthetic talker's utterance).
    """
    words = [w.strip(".,;:!?").lower() for w in utterance.text.split()]
    phones = [p for p in utterance.phones if p.label != PAUSE]
    out, k = [], 0
    for w in words:
        pron = list(pronounce(w))
        got = [p.label for p in phones[k:k + len(pron)]]
        if not pron or got != pron:
            raise ValueError(f"utterance {utterance.id}: word {w!r} ({' '.join(pron)}) does not match its phones "
                             f"{' '.join(got)}; speech audio needs the synthetic talker's text and phones")
        out.append((w, phones[k].start, phones[k + len(pron) - 1].end))
        k += len(pron)
    if k != len(phones):
        raise ValueError(f"utterance {utterance.id}: {len(phones) - k} phones left after the text's words")
    return out


def read_wav(path_or_bytes) -> tuple[np.ndarray, int]:
    """(samples float32 in [-1, 1], sample rate) of a 16-bit mono WAV file or its bytes."""
    src = io.BytesIO(path_or_bytes) if isinstance(path_or_bytes, (bytes, bytearray)) else str(path_or_bytes)
    with wave.open(src, "rb") as w:
        if w.getsampwidth() != 2 or w.getnchannels() != 1:
            raise ValueError(f"{path_or_bytes if not isinstance(path_or_bytes, bytes) else 'audio'}: expected "
                             f"16-bit mono WAV, got {8 * w.getsampwidth()}-bit with {w.getnchannels()} channels")
        x = np.frombuffer(w.readframes(w.getnframes()), dtype="<i2").astype(np.float32) / 32768.0
        return x, w.getframerate()


def _speak(words, exe) -> np.ndarray:
    ssml = "<speak>" + f'<break time="{_BREAK_MS}ms"/>'.join(words) + "</speak>"
    r = subprocess.run([exe, "-m", "--stdout", "-v", "en-us", ssml], capture_output=True, check=True, timeout=60)
    x, sr = read_wav(r.stdout)
    if sr != SAMPLE_RATE:  # espeak-ng's voices speak at 22,050 Hz; resample anything else linearly
        t = np.arange(int(len(x) * SAMPLE_RATE / sr)) * sr / SAMPLE_RATE
        x = np.interp(t, np.arange(len(x)), x).astype(np.float32)
    return x


def _envelope(x, width):
    k = np.ones(width, np.float32) / width
    return np.sqrt(np.convolve(x.astype(np.float32) ** 2, k, mode="same"))


def _split_words(x, n_words) -> list[tuple[int, int]] | None:
    """Sample ranges of ``n_words`` words separated by the longest silences, or None."""
    env = _envelope(x, int(0.01 * SAMPLE_RATE))
    loud = env > 0.03 * env.max()
    if not loud.any():
        return None
    idx = np.flatnonzero(loud)
    first, last = idx[0], idx[-1] + 1
    quiet = ~loud[first:last]
    # runs of silence inside the speech
    d = np.diff(np.r_[0, quiet.astype(np.int8), 0])
    s, e = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    gaps = [(b - a, a + first, b + first) for a, b in zip(s, e) if b - a >= _MIN_GAP_S * SAMPLE_RATE]
    if len(gaps) < n_words - 1:
        return None
    cut = sorted(gaps, reverse=True)[:n_words - 1]
    cut = sorted((a, b) for _, a, b in cut)
    bounds, start = [], first
    for a, b in cut:
        bounds.append((start, a))
        start = b
    bounds.append((start, last))
    return bounds


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
    if n_out <= 0:
        return np.zeros(0, np.float32)
    win, hop, tol = _WIN, _WIN // 2, _WIN // 4
    if len(x) < 2 * win or n_out < 2 * win:  # too short to overlap-add: plain resampling
        t = np.linspace(0, max(len(x) - 1, 0), n_out)
        return np.interp(t, np.arange(len(x)), x).astype(np.float32) if len(x) else np.zeros(n_out, np.float32)
    alpha = (len(x) - win) / max(n_out - win, 1)
    pad = np.concatenate([np.zeros(tol, np.float32), x, np.zeros(win + tol, np.float32)])
    w = np.hanning(win + 1)[:win].astype(np.float32)
    out = np.zeros(n_out + win, np.float32)
    norm = np.zeros(n_out + win, np.float32)
    prev = 0
    for k in range(0, n_out, hop):
        nominal = min(int(round(k * alpha)), len(x) - win)
        if k == 0:
            pos = nominal
        else:
            target = pad[tol + prev + hop: tol + prev + hop + win]   # natural continuation of the last frame
            seg = pad[nominal: nominal + win + 2 * tol]
            c = np.correlate(seg, target, mode="valid")
            pos = nominal - tol + int(np.argmax(c))
            pos = min(max(pos, 0), len(x) - win)
        out[k:k + win] += w * pad[tol + pos: tol + pos + win]
        norm[k:k + win] += w
        prev = pos
    norm[norm < 1e-3] = 1.0
    return (out / norm)[:n_out]


def utterance_audio(utterance, exe=None) -> tuple[np.ndarray, dict]:
    """The speech of one synthetic utterance, aligned to its phones.

    Returns
    -------
    samples : ndarray of shape (round(duration * 22050),) float32
    info : dict
        ``words`` (count), ``split`` (True when every word was cut and placed on its own,
        False when the sentence was stretched as a whole), ``stretch`` (per placed
        segment, its duration in the talker's timing / espeak-ng's).
    """
    exe = exe or _require_espeak()
    spans = word_spans(utterance)
    duration = utterance.phones[-1].end if utterance.phones else 0.0
    out = np.zeros(int(round(duration * SAMPLE_RATE)), np.float32)
    if not spans:
        return out, {"words": 0, "split": True, "stretch": np.zeros(0)}
    x = _speak([w for w, _, _ in spans], exe)
    parts = _split_words(x, len(spans))
    placed = ([(x[a:b], s, e) for (a, b), (_, s, e) in zip(parts, spans)] if parts is not None else
              [(x[slice(*_trim(x))], spans[0][1], spans[-1][2])])
    fade = int(0.005 * SAMPLE_RATE)
    stretch = []
    for seg, s, e in placed:
        i0, i1 = int(round(s * SAMPLE_RATE)), min(int(round(e * SAMPLE_RATE)), len(out))
        if i1 - i0 < 2:
            continue
        y = time_stretch(seg, i1 - i0)
        stretch.append((i1 - i0) / max(len(seg), 1))
        f = min(fade, len(y) // 2)
        if f:
            ramp = np.linspace(0, 1, f, dtype=np.float32)
            y[:f] *= ramp
            y[-f:] *= ramp[::-1]
        out[i0:i1] += y
    peak = float(np.abs(out).max())
    if peak > 0.98:
        out *= 0.98 / peak
    return out, {"words": len(spans), "split": parts is not None, "stretch": np.array(stretch)}


def _trim(x):
    env = _envelope(x, int(0.01 * SAMPLE_RATE))
    idx = np.flatnonzero(env > 0.03 * env.max()) if len(x) and env.max() > 0 else np.array([0, len(x) - 1])
    return int(idx[0]), int(idx[-1]) + 1


def add_speech_audio(corpus, folder, *, progress=None, workers: int = 2):
    """Write one WAV per utterance into ``folder`` and return the corpus with ``audio`` set.

    Parameters
    ----------
    corpus : Corpus
        The synthetic talker's corpus (text and phones of its utterances).
    folder : path
        Created if missing; files ``<utterance id>.wav``. Existing files are reused.
    progress : callable(stage, done, total) or None
    workers : int, default=2
        espeak-ng processes at once.

    Returns
    -------
    Corpus
        The same frames and labels; each utterance's ``audio`` is its WAV's absolute path.

    Raises
    ------
    SpeechAudioUnavailable
        When espeak-ng is not installed.
    """
    exe = _require_espeak()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    utts = list(corpus.utterances)
    paths = [(folder / f"{u.id}.wav").resolve() for u in utts]
    todo = [k for k, p in enumerate(paths) if not p.is_file()]
    done = 0
    report(progress, "speech audio", 0, len(todo))

    def one(k):
        samples, _ = utterance_audio(utts[k], exe)
        write_wav_atomic(paths[k], samples, SAMPLE_RATE)

    with ThreadPoolExecutor(max_workers=max(1, int(workers))) as pool:
        for _ in pool.map(one, todo):
            done += 1
            report(progress, "speech audio", done, len(todo))
    new = [dataclasses.replace(u, audio=str(p)) for u, p in zip(utts, paths)]
    return dataclasses.replace(corpus, utterances=new)
