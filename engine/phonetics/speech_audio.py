"""Speech audio for the synthetic talker: espeak-ng, each phone placed on the talker's phone.

The talker's utterances carry phone timings but no sound. :func:`add_speech_audio`
gives each utterance a WAV file (22,050 Hz, 16-bit mono) that plays in the explorer
like the audio of a recorded corpus (``Utterance.audio``). Two methods:

``"phones"`` (espeak-ng's library, :mod:`engine.phonetics.espeak_phones`; the default)
    1. the utterance's own phones are spoken as espeak-ng phoneme input
       (``[[D@ k'at s'at]]``: :data:`~engine.phonetics.espeak_phones.ESPEAK_PHONE` maps every
       talker phone to one espeak-ng phone; the stress marks come from the CMU
       dictionary's stress digits), so espeak-ng says exactly the talker's phones;
    2. its phoneme events give the sample at which each phone starts;
    3. one WSOLA pass (:func:`time_warp`: overlap-add of 23 ms Hann windows placed by
       cross-correlation within ±6 ms, so the pitch is kept) stretches the sound
       piecewise linearly so that each phone's start lands on the talker's phone start
       and the last phone ends with the talker's last phone. There are no joins
       between phones (one continuous pass), so none can click.

``"words"`` (the espeak-ng program; the fallback without the library)
    espeak-ng speaks the sentence's text as SSML with a 250 ms break between words;
    the words are cut at the longest silences and each is time-stretched to exactly the
    span its phones take (a sentence whose silences cannot be matched to its words is
    stretched as a whole). Inside a word espeak-ng's own phone timing remains, and it
    pronounces from its own lexicon.

Without either, :func:`add_speech_audio` raises :class:`SpeechAudioUnavailable` with one
line saying how to install espeak-ng. The audio folder holds ``speech-audio.json``
(:data:`AUDIO_VERSION` and the method); files made by another version or method are
made again, not reused.
"""
from __future__ import annotations

import dataclasses
import io
import json
import shutil
import subprocess
import threading
import wave
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from engine.files.atomic import write_text_atomic, write_wav_atomic
from engine.phonetics import espeak_phones
from engine.phonetics.phones import PAUSE, is_vowel, pronounce
from engine.phonetics.time_warp import time_stretch, time_warp
from engine.progress import report

__all__ = ["SpeechAudioUnavailable", "AUDIO_VERSION", "espeak_path", "audio_method", "word_spans",
           "phone_mnemonics", "time_stretch", "time_warp", "utterance_audio", "add_speech_audio",
           "planned_speech_audio", "read_wav",
           "SAMPLE_RATE"]

SAMPLE_RATE = 22050
#: Version of the audio files: 1 = words placed on their spans, 2 = every phone on its start.
AUDIO_VERSION = 2
_MANIFEST = "speech-audio.json"
_BREAK_MS = 250
_MIN_GAP_S = 0.12
_FADE_S = 0.005
#: how many unexpected espeak-ng phone events may come between two expected ones
_LOOKAHEAD = 3
#: an espeak-ng phone shorter than this shares its neighbour's span (espeak-ng folds some /l/ into the vowel)
_MIN_PHONE_S = 0.002


class SpeechAudioUnavailable(RuntimeError):
    """espeak-ng is not installed, so the synthetic talker has no audio."""


def espeak_path() -> str | None:
    """Path of the ``espeak-ng`` program, or None when it is not installed."""
    return shutil.which("espeak-ng")


def audio_method() -> str:
    """``"phones"`` when espeak-ng's library can be loaded, else ``"words"`` when its program
    is installed.

    Raises
    ------
    SpeechAudioUnavailable
        When neither is installed.
    """
    if espeak_phones.espeak_library() is not None:
        return "phones"
    _require_espeak()
    return "words"


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
    longest = sorted(gaps, reverse=True)[:n_words - 1]
    cut = sorted((a, b) for _, a, b in longest)
    bounds, start = [], first
    for a, b in cut:
        bounds.append((start, a))
        start = b
    bounds.append((start, last))
    return bounds


def phone_mnemonics(utterance, spans=None) -> list[str]:
    """espeak-ng's phoneme for each phone of ``utterance`` (pauses included), with stress marks.

    A vowel carries ``'`` (primary) or ``,`` (secondary stress) as the CMU dictionary
    stresses it in its word. Phones are grouped into words by :func:`word_spans`.

    Parameters
    ----------
    utterance : Utterance
    spans : list of (word, start s, end s) or None
        ``word_spans(utterance)`` when the caller has it already; computed when None.

    Returns
    -------
    list of str, one per phone of ``utterance.phones``
    """
    from engine.phonetics.phones import _cmu_entry

    words = iter(word_spans(utterance) if spans is None else spans)
    out: list[str] = []
    word_left = 0
    marks: list[str] = []
    for p in utterance.phones:
        if p.label == PAUSE:
            out.append(espeak_phones.ESPEAK_PHONE[PAUSE])
            continue
        if word_left == 0:
            w = next(words)[0]
            pron = pronounce(w)
            word_left = len(pron)
            marks = _stress_marks(pron, _cmu_entry(w) or "")
        out.append(marks[len(marks) - word_left] + espeak_phones.ESPEAK_PHONE[p.label])
        word_left -= 1
    return out


def _stress_marks(phones, cmu: str) -> list[str]:
    """The stress mark ('', "'" or ",") of each phone of a word, from its CMU stress digits."""
    digits = [t[-1] for t in cmu.split() if t[-1:].isdigit()]
    vowels = [k for k, p in enumerate(phones) if is_vowel(p)]  # uw, er included
    if len(vowels) > len(digits):  # 'fire' AY1 ER0 -> ay ax: the extra schwa after ay/aw is unstressed
        vowels = [k for k in vowels if not (phones[k] == "ax" and k and phones[k - 1] in ("ay", "aw"))]
    marks = [""] * len(phones)
    if len(vowels) != len(digits):
        if vowels:
            marks[vowels[0]] = "'"
        return marks
    for k, d in zip(vowels, digits):
        marks[k] = {"1": "'", "2": ","}.get(d, "")
    return marks


def _match_events(expected, events):
    """Sample at which each expected phone starts (None for the second of two phones espeak-ng
    spoke as one, e.g. ``aI`` + ``@`` as ``aI@``), and the end of the last; None if they differ."""
    bare = [m.lstrip("',") for m in expected]

    def same(k, m):
        name = events[k][0] if k < len(events) else None
        return name == m or (m == "_" and name is not None and name.startswith("_"))

    starts: list[int | None] = []
    e = i = 0
    while i < len(bare):
        m = bare[i]
        pair = m + bare[i + 1] if i + 1 < len(bare) else None
        for d in range(_LOOKAHEAD + 1):
            if same(e + d, m):
                starts.append(events[e + d][1])
                i += 1
                break
            if pair is not None and e + d < len(events) and events[e + d][0] == pair:
                starts += [events[e + d][1], None]
                i += 2
                break
        else:
            # one phone said as another (espeak-ng assimilates: 'n' before 'k' as 'N'), the next in step
            if (e < len(events) and not events[e][0].startswith("_")
                    and (i + 1 == len(bare) or same(e + 1, bare[i + 1]))):
                starts.append(events[e][1])
                i += 1
                d = 0
            else:
                return None
        e += d + 1
    end = events[e][1] if e < len(events) else None
    return starts, end


def _share_spans(src, dst, min_len):
    """Phone starts in espeak-ng's sound, the gaps filled: a phone espeak-ng spoke together with
    the one before it (start None: one event for both) or gave less than ``min_len`` samples
    (espeak-ng folds some /l/ into the vowel before) shares the two phones' joint span in
    proportion to their durations in the talker's timing."""
    src = list(src)

    def share(i):
        a, b = src[i - 1], src[i + 1]
        src[i] = a + (b - a) * (dst[i] - dst[i - 1]) / (dst[i + 1] - dst[i - 1])

    for i in range(1, len(src) - 1):
        if src[i] is None:
            share(i)
    for i in range(1, len(src) - 1):
        if src[i + 1] - src[i] < min_len <= (src[i + 1] - src[i - 1]) / 2:
            share(i)
    return np.array(src, np.float64)


def _phones_audio(utterance, worker, spans) -> tuple[np.ndarray, dict] | None:
    """The phone method; None when espeak-ng's phone events do not follow the talker's phones.

    ``spans``: ``word_spans(utterance)``.
    """
    phones = utterance.phones
    duration = phones[-1].end if phones else 0.0
    out = np.zeros(int(round(duration * SAMPLE_RATE)), np.float32)
    speech = [k for k, p in enumerate(phones) if p.label != PAUSE]
    if not speech:
        return out, {"method": "phones", "phones": 0, "stretch": np.zeros(0), "source": np.zeros(0),
                     "target": np.zeros(0)}
    k0, k1 = speech[0], speech[-1] + 1
    mnem = phone_mnemonics(utterance, spans)[k0:k1]
    word_starts = {s for _, s, _ in spans}
    groups, prev_pause = [], True
    for p, m in zip(phones[k0:k1], mnem):
        if p.label == PAUSE or prev_pause or p.start in word_starts:
            groups.append(m)
        else:
            groups[-1] += m
        prev_pause = p.label == PAUSE
    raw, rate, events = worker.speak("[[" + " ".join(groups) + "]]")
    x = np.frombuffer(raw, "<i2").astype(np.float32) / 32768.0
    if rate != SAMPLE_RATE:
        raise espeak_phones.EspeakLibraryError(f"espeak-ng library speaks at {rate} Hz, expected {SAMPLE_RATE}")
    matched = _match_events(mnem, events)
    if matched is None:
        return None
    starts, end = matched
    dst = np.array([p.start for p in phones[k0:k1]] + [phones[k1 - 1].end]) * SAMPLE_RATE
    src = _share_spans(starts + [end if end is not None else len(x)], dst, _MIN_PHONE_S * SAMPLE_RATE)
    i0, i1 = int(round(dst[0])), min(int(round(dst[-1])), len(out))
    y = time_warp(x, src, dst - i0, i1 - i0) if i1 - i0 >= 2 else np.zeros(max(i1 - i0, 0), np.float32)
    out[i0:i1] = _fade(y)
    _limit(out)
    stretch = np.diff(dst) / np.maximum(np.diff(src), 1.0)
    return out, {"method": "phones", "phones": k1 - k0, "stretch": stretch, "source": src, "target": dst,
                 "espeak": x}


def _fade(y):
    """``y`` faded in and out over :data:`_FADE_S` (at most half its length each), in place."""
    f = min(int(_FADE_S * SAMPLE_RATE), len(y) // 2)
    if f:
        ramp = np.linspace(0, 1, f, dtype=np.float32)
        y[:f] *= ramp
        y[-f:] *= ramp[::-1]
    return y


def _limit(out):
    peak = float(np.abs(out).max()) if len(out) else 0.0
    if peak > 0.98:
        out *= 0.98 / peak


def utterance_audio(utterance, exe=None, *, method=None, worker=None) -> tuple[np.ndarray, dict]:
    """The speech of one synthetic utterance, aligned to its phones.

    Parameters
    ----------
    utterance : Utterance
        A synthetic talker's utterance (text and phones).
    exe : str or None
        The espeak-ng program (the word method; found when None).
    method : {"phones", "words"} or None
        None: :func:`audio_method`. ``"phones"`` falls back to ``"words"`` for an
        utterance whose phones espeak-ng does not speak as given.
    worker : EspeakWorker or None
        A running espeak-ng library process (the phone method); one is started when None.

    Returns
    -------
    samples : ndarray of shape (round(duration * 22050),) float32
    info : dict
        ``method`` (the one used). Phone method: ``phones`` (count), ``stretch`` (per
        phone, its duration in the talker's timing / espeak-ng's), ``source`` /
        ``target`` (shape (phones + 1,): espeak-ng's phone starts and end, in samples of
        ``espeak``, and where they were put, in samples of the output), ``espeak`` (its
        unwarped sound). Word method: ``words``, ``split`` (True when every word was cut
        and placed on its own), ``stretch`` (per placed segment).
    """
    method = method or audio_method()
    if method not in ("phones", "words"):
        raise ValueError(f"method must be 'phones' or 'words', got {method!r}")
    spans = word_spans(utterance)  # once: both methods place the words by it
    if method == "phones":
        own = worker is None
        worker = worker or espeak_phones.EspeakWorker()
        try:
            got = _phones_audio(utterance, worker, spans)
        except espeak_phones.EspeakLibraryError:
            if espeak_path() is None and exe is None:
                raise
            got = None  # the library failed: the program may still speak the words
        finally:
            if own:
                worker.close()
        if got is not None:
            return got
    return _words_audio(utterance, exe or _require_espeak(), spans)


def _words_audio(utterance, exe, spans) -> tuple[np.ndarray, dict]:
    """The word method (espeak-ng program): each word stretched to its span (``word_spans(utterance)``)
    in the talker's timing."""
    duration = utterance.phones[-1].end if utterance.phones else 0.0
    out = np.zeros(int(round(duration * SAMPLE_RATE)), np.float32)
    if not spans:
        return out, {"method": "words", "words": 0, "split": True, "stretch": np.zeros(0)}
    x = _speak([w for w, _, _ in spans], exe)
    parts = _split_words(x, len(spans))
    placed = ([(x[a:b], s, e) for (a, b), (_, s, e) in zip(parts, spans)] if parts is not None else
              [(x[slice(*_trim(x))], spans[0][1], spans[-1][2])])
    stretch = []
    for seg, s, e in placed:
        i0, i1 = int(round(s * SAMPLE_RATE)), min(int(round(e * SAMPLE_RATE)), len(out))
        if i1 - i0 < 2:
            continue
        stretch.append((i1 - i0) / max(len(seg), 1))
        out[i0:i1] += _fade(time_stretch(seg, i1 - i0))
    _limit(out)
    return out, {"method": "words", "words": len(spans), "split": parts is not None,
                 "stretch": np.array(stretch)}


def _trim(x):
    env = _envelope(x, int(0.01 * SAMPLE_RATE))
    idx = np.flatnonzero(env > 0.03 * env.max()) if len(x) and env.max() > 0 else np.array([0, len(x) - 1])
    return int(idx[0]), int(idx[-1]) + 1


def planned_speech_audio(corpus, folder):
    """``corpus`` with each utterance's ``audio`` naming ``<folder>/<utterance id>.wav``, whether or not the
    file exists yet: :func:`add_speech_audio` with the same folder writes them there (a player finds
    each one once it is written).

    Raises
    ------
    SpeechAudioUnavailable
        When espeak-ng is not installed (nothing would ever be written).
    """
    audio_method()
    folder = Path(folder).resolve()
    new = [dataclasses.replace(u, audio=str(folder / f"{u.id}.wav")) for u in corpus.utterances]
    return dataclasses.replace(corpus, utterances=new, history=list(corpus.history))


def add_speech_audio(corpus, folder, *, progress=None, workers: int = 2):
    """Write one WAV per utterance into ``folder`` and return the corpus with ``audio`` set.

    Parameters
    ----------
    corpus : Corpus
        The synthetic talker's corpus (text and phones of its utterances).
    folder : path
        Created if missing; files ``<utterance id>.wav`` and ``speech-audio.json``.
        Existing files are reused when that file names this :data:`AUDIO_VERSION` and
        method; otherwise they are made again.
    progress : callable(stage, done, total) or None
        May raise :class:`~engine.progress.Cancelled` to stop (files written so far stay).
    workers : int, default=2
        espeak-ng processes at once.

    Returns
    -------
    Corpus
        The same frames and labels; each utterance's ``audio`` is its WAV's absolute
        path; one ``history`` line says which method made the audio.

    Raises
    ------
    SpeechAudioUnavailable
        When espeak-ng is not installed.
    """
    method = audio_method()
    exe = espeak_path()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    utts = list(corpus.utterances)
    paths = [(folder / f"{u.id}.wav").resolve() for u in utts]
    state = {"version": AUDIO_VERSION, "method": method}
    manifest = folder / _MANIFEST
    try:
        fresh = json.loads(manifest.read_text()) == state
    except (OSError, ValueError):
        fresh = False
    if not fresh:  # made by another version or method: not reused
        for p in paths:
            p.unlink(missing_ok=True)
        write_text_atomic(manifest, json.dumps(state))
    todo = [k for k, p in enumerate(paths) if not p.is_file()]
    done = 0
    report(progress, "speech audio", 0, len(todo))
    local, started, lock = threading.local(), [], threading.Lock()

    def one(k):
        worker = None
        if method == "phones":
            worker = getattr(local, "worker", None)
            if worker is None or not worker.running:  # none yet, or the last one failed (hung, crashed)
                worker = local.worker = espeak_phones.EspeakWorker()
                with lock:
                    started.append(worker)
        samples, info = utterance_audio(utts[k], exe, method=method, worker=worker)
        write_wav_atomic(paths[k], samples, SAMPLE_RATE)
        return info["method"]

    used = []
    pool = ThreadPoolExecutor(max_workers=max(1, int(workers)))
    try:
        for m in pool.map(one, todo):
            used.append(m)
            done += 1
            report(progress, "speech audio", done, len(todo))
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        for w in started:
            w.close()
    new = [dataclasses.replace(u, audio=str(p)) for u, p in zip(utts, paths)]
    history = list(corpus.history) + [_history_line(method, len(utts), used.count("words"), len(todo))]
    return dataclasses.replace(corpus, utterances=new, history=history)


def _history_line(method, n, fell_back, made) -> str:
    reused = f"{n - made} reused, {made} made" if made < n else f"{n} made"
    if method == "phones":
        back = (f"; {fell_back} of the {made} made now word by word (the library did not speak their phones "
                f"as given)") if fell_back else ""
        return (f"speech audio: espeak-ng library, every phone placed on the talker's phone start "
                f"({n} utterances, {reused}{back})")
    return (f"speech audio: espeak-ng program, each word stretched to the talker's word span, phones inside a "
            f"word not aligned ({espeak_phones.LIBRARY_NAME} not found; {n} utterances, {reused})")
