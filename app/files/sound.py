"""Sound for everything the explorer shows that has sound (Qt-free).

* A recording opened directly (File › Open, ``lipspace explore FILE``) keeps its sound as
  ``lipspace import`` keeps it: a Haskins / MVIEW ``.mat`` file's ``AUDIO`` entry, a video's
  audio track. The WAV files go to the cache (``<cache>/sound/recording-<key>/``, keyed by
  the file's path, size and time), never beside the user's data.
* Typed text that is synthesised speaks: espeak-ng says the text's own phones, each moved
  onto its phone's time in the targets (:func:`engine.phonetics.speech_audio.utterance_audio`),
  into ``<cache>/sound/speech-<key>.wav``. Without espeak-ng the synthesis stays silent and
  :func:`speech_for_targets` says why (once, in the window's status bar).
"""
from __future__ import annotations

import hashlib
from dataclasses import replace
from pathlib import Path

__all__ = ["sound_dir", "recording_key", "read_with_sound", "speech_for_targets", "SoundNote", "resolve_audio_path",
           "playback_audio"]


class SoundNote(RuntimeError):
    """Why a synthesis has no sound (espeak-ng missing, a text it cannot say): said, never raised to the user."""


def resolve_audio_path(audio, corpus_source=None) -> Path | None:
    """The audio file of an utterance, or None when it has none or it is missing.

    Relative paths are taken relative to the corpus file's folder (``corpus_source``).
    """
    if not audio:
        return None
    p = Path(audio)
    if not p.is_absolute() and corpus_source:
        p = Path(corpus_source).resolve().parent / p
    return p if p.is_file() else None


def playback_audio(state):
    """``(wav path, frame rate)`` of the sound that plays with playback (frame 0 at the file's start), or None.

    The utterance's own sound while its captured trajectory is shown (a re-synthesis of it
    plays on its timeline); else the synthesised trajectory's spoken text (``extra["audio"]``).
    """
    orig, syn = state.original, state.synthetic
    if orig is not None and state.utterance is not None and state.manifold is not None:
        u = state.manifold.corpus_.utterance(state.utterance)
        path = resolve_audio_path(u.audio, (state.source or {}).get("path"))
        return None if path is None else (path, float(orig.rate))
    if syn is not None:
        path = resolve_audio_path((syn.extra or {}).get("audio"))
        return None if path is None else (path, float(syn.rate))
    return None


def sound_dir() -> Path:
    """Where the explorer keeps the sound it extracts or makes: ``<cache>/sound``."""
    from app.files.cache import cache_dir

    return cache_dir() / "sound"


def _mark(entry: Path) -> None:
    """Record ``entry`` as Lipspace's own (:mod:`engine.files.ownership`): 'lipspace cache --clear' may delete it."""
    from app.files.cache import cache_dir
    from engine.files.ownership import mark

    mark(entry, cache_dir())


def recording_key(path) -> str:
    """16 hex digits naming a recording's extracted sound: its resolved path, size and modification time."""
    p = Path(path).resolve()
    st = p.stat()
    return hashlib.sha256(f"{p}|{st.st_size}|{st.st_mtime_ns}".encode()).hexdigest()[:16]


def read_with_sound(path):
    """Read a foreign recording (:func:`engine.io.read_corpus`) with its sound, as ``lipspace import`` does.

    A video's audio track and an MVIEW ``.mat`` file's ``AUDIO`` entry become WAV files in
    ``sound_dir() / "recording-<key>"`` (made once per file version); other formats read as
    they are (a ``<stem>.wav`` beside the file is found by the readers). A ``.mat`` file
    without an ``AUDIO`` entry reads silent.
    """
    from engine.io import ImportFormatError, detect_format, read_corpus

    fmt = detect_format(path)
    if fmt not in ("video", "mview"):
        return read_corpus(path)
    folder = sound_dir() / f"recording-{recording_key(path)}"
    if fmt == "video":
        folder.mkdir(parents=True, exist_ok=True)
        corpus = read_corpus(path, audio_dir=folder)
        _mark(folder)
        return corpus
    corpus = read_corpus(path)
    if any(u.audio for u in corpus.utterances):
        return corpus  # a <stem>.wav beside it, as the reader found it
    from engine.io import write_audio

    wav = folder / (Path(path).stem + ".wav")
    if not wav.is_file():
        try:
            folder.mkdir(parents=True, exist_ok=True)
            write_audio(path, wav)
        except ImportFormatError:  # no AUDIO entry (or no finite sample): silent, as the file is
            return corpus
        _mark(folder)
    return replace(corpus, utterances=[replace(u, audio=str(wav)) for u in corpus.utterances])


def _spoken_phones(targets, text: str):
    """The targets' phones labelled with the text's own pronunciation (the talker's phone set espeak-ng says),
    or None when they do not match one to one (the text's phones, bracketed by pauses or not)."""
    from engine.phonetics.phones import PAUSE, pronounce
    from engine.recordings.corpus import PhoneInterval

    said = list(pronounce(text))
    phones = list(targets.phones)
    if len(phones) == len(said) + 2:
        said = [PAUSE, *said, PAUSE]
    if len(phones) != len(said):
        return None
    return tuple(PhoneInterval(p.start, p.end, lab) for p, lab in zip(phones, said))


def speech_for_targets(targets, text: str) -> Path:
    """A WAV of ``text`` spoken on the timing of ``targets`` (from :func:`engine.phonetics.targets.targets_from_text`).

    Made once per text and timing (``sound_dir() / "speech-<key>.wav"``, 22,050 Hz).

    Raises
    ------
    SoundNote
        Saying why there is no sound (espeak-ng not installed, the text not spoken as its phones).
    """
    import numpy as np

    from engine.files.atomic import write_wav_atomic
    from engine.phonetics.speech_audio import SAMPLE_RATE, SpeechAudioUnavailable, utterance_audio
    from engine.recordings.corpus import Utterance

    phones = _spoken_phones(targets, text)
    if phones is None:
        raise SoundNote(f"the synthesis is silent: the phones of {text[:40]!r} were changed by the corpus's phone "
                        "set, so espeak-ng cannot say them on their times")
    key = hashlib.sha256(repr((text, [(round(p.start, 6), round(p.end, 6), p.label) for p in phones])).encode())
    wav = sound_dir() / f"speech-{key.hexdigest()[:16]}.wav"
    if wav.is_file():
        return wav
    u = Utterance("synthesis", 0, int(targets.n_frames), phones, None, text)
    try:
        samples, _info = utterance_audio(u)
    except SpeechAudioUnavailable as exc:
        raise SoundNote(f"the synthesis is silent: {exc}") from None
    except (ValueError, RuntimeError) as exc:
        raise SoundNote(f"the synthesis is silent: espeak-ng could not say {text[:40]!r} ({exc})") from None
    wav.parent.mkdir(parents=True, exist_ok=True)
    write_wav_atomic(wav, np.asarray(samples, np.float64), SAMPLE_RATE)
    _mark(wav)
    return wav
