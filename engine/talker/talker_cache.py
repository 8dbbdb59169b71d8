"""The cache of the synthetic talker's corpora: generated once per parameters, then read back.

A corpus is cached under :func:`cache_folder` in a file named from its preset and opt-in
variants (:func:`cache_token`) and a key of the talker's parameters, :data:`GENERATOR_VERSION`
and the generator's code (:func:`talker_key`), so a corpus made by older code or with other
parameters is never reused. Its speech audio, when asked for, lives beside it in
:func:`audio_folder`. :func:`load_synthetic` is the one entry: read the cache, or generate and
write it.
"""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

from engine.progress import ProgressFn, report
from engine.recordings.corpus import Corpus, CorpusError
from engine.talker.synthetic_talker import _VARIANT_DEFAULTS, GENERATOR_VERSION, LIP_MODEL_AXES, SyntheticTalker

__all__ = ["load_synthetic", "cache_folder", "cache_path", "audio_folder", "talker_key", "cache_token",
           "generator_fingerprint", "GENERATOR_MODULES"]

#: the modules whose code makes the talker's corpus (the talker, its gestures, the lip surface, the
#: phonetics and the corpus it fills): an edit to any of them changes the cache key
GENERATOR_MODULES = ("engine.talker.synthetic_talker", "engine.talker.gestures", "engine.talker.lipmodel",
                     "engine.phonetics.phones", "engine.recordings.corpus", "engine.recordings.utterances",
                     "engine.recordings.corpus_format")


def cache_folder(override: str | os.PathLike[str] | None = None) -> Path:
    """Folder of cached corpora: ``override``, else ``$LIPSPACE_CACHE_DIR``, else the
    platform's user cache folder for ``lipspace``."""
    if override is not None:
        return Path(override)
    from engine.files.userdirs import user_dir

    return user_dir("cache", "LIPSPACE_CACHE_DIR")


def generator_fingerprint() -> str:
    """A hash of the synthetic talker's code (:data:`GENERATOR_MODULES`)."""
    from engine.files.persist import source_fingerprint

    return source_fingerprint(GENERATOR_MODULES)


def _cache_key(params: dict) -> str:
    # the generator's code is part of the key: an edit without a GENERATOR_VERSION bump still regenerates
    blob = json.dumps({"version": GENERATOR_VERSION, "code": generator_fingerprint(), **params}, sort_keys=True,
                      default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


def cache_path(preset: str = "default", *, cache_dir: str | os.PathLike[str] | None = None,
               **params: Any) -> Path:
    """Where :func:`load_synthetic` caches the corpus of ``preset`` with ``params``; its speech audio
    goes in the folder of the same name ending ``-audio`` (:func:`audio_folder`)."""
    return cache_folder(cache_dir) / f"synthetic-{cache_token(preset, **params)}-{talker_key(preset, **params)}.npz"


def audio_folder(corpus_path: str | os.PathLike[str]) -> Path:
    """The folder of a cached corpus's speech audio: its file name without ``.npz``, ending ``-audio``."""
    corpus_path = Path(corpus_path)
    return corpus_path.with_name(corpus_path.stem + "-audio")


def talker_key(preset: str = "default", **params: Any) -> str:
    """The key of the corpus :class:`SyntheticTalker` ``(preset=preset, **params)`` generates: a hash of its
    parameters, :data:`GENERATOR_VERSION` and the generator's code (:func:`generator_fingerprint`).
    ValueError for parameters the talker refuses."""
    talker = SyntheticTalker(preset=preset, **params)
    talker._validate()
    key = {k: v for k, v in talker.get_params().items() if not (k in _VARIANT_DEFAULTS and v == _VARIANT_DEFAULTS[k])}
    return _cache_key(key)


def cache_token(preset: str = "default", **params: Any) -> str:
    """The preset part of a cached talker's file name: the preset, and the opt-in variants
    (``_calibrated``, ``_tissue``) so that the cache keeps one entry of each apart."""
    out = preset
    if params.get("kinematics", "classic") != "classic":
        out += f"_{params['kinematics']}"
    if params.get("tissue", False):
        out += "_tissue"
    return out


def load_synthetic(*, preset: str = "default", progress: ProgressFn = None,
                   cache_dir: str | os.PathLike[str] | None = None, audio: bool = False,
                   save_later: list | None = None, **params: Any) -> Corpus:
    """The synthetic corpus for ``preset``, generated once and cached.

    Parameters
    ----------
    preset : {"small", "default", "paper", "multi"}
    progress : callable(stage, done, total) or None
    cache_dir : path or None
        Overrides ``$LIPSPACE_CACHE_DIR`` and the user cache folder.
    audio : bool, default=False
        Give every utterance speech audio (:mod:`engine.phonetics.speech_audio`, espeak-ng),
        written once beside the cached corpus (``<cache file>-audio/``). Without
        espeak-ng the corpus has no audio and its ``history`` says why.
    save_later : list or None
        A list: a corpus generated here is not written to the cache here; a job writing it
        (no arguments, never raising) is appended for the caller to run (the explorer runs it
        in the background, after its window shows the talker).
    **params
        Further :class:`SyntheticTalker` parameters (``seed``, ``n_sentences``, ...).

    Returns
    -------
    Corpus
    """
    talker = SyntheticTalker(preset=preset, **params)
    path = cache_path(preset, cache_dir=cache_dir, **params)
    if path.is_file():
        report(progress, "loading cache", 0, 1)
        try:
            from engine.files.persist import read_npz

            # the frames mapped from the file, read-only: pages come in as they are used (the explorer's
            # start reads them once, to check them and to project them)
            corpus = Corpus.from_arrays(read_npz(path, memory_map=None), source=str(path), base=path.resolve().parent)
            # the lip model's unit and axes (cache files written before corpora named them)
            corpus.units, corpus.axes = "mm", LIP_MODEL_AXES
            report(progress, "loading cache", 1, 1)
            return _with_audio(corpus, path, progress) if audio else corpus
        except (CorpusError, OSError, ValueError):
            pass  # damaged cache file: regenerate it
    corpus = talker.generate(progress=progress)

    def save() -> None:
        from engine.files.ownership import mark

        try:
            corpus.save(path)
            mark(path, path.parent)  # Lipspace's own: pruning and 'lipspace cache --clear' may delete it
        except OSError:
            pass  # a read-only cache folder only costs regeneration next time

    if save_later is not None:
        save_later.append(save)
    else:
        report(progress, "saving cache", 0, 1)
        save()
        report(progress, "saving cache", 1, 1)
    return _with_audio(corpus, path, progress) if audio else corpus


def _with_audio(corpus: Corpus, path: Path, progress: ProgressFn) -> Corpus:
    """The corpus with speech audio in ``<path stem>-audio/``, or without it and a note why."""
    import subprocess

    from engine.files.ownership import mark, owned
    from engine.phonetics.speech_audio import SpeechAudioUnavailable, add_speech_audio

    folder = audio_folder(path)
    made = not folder.exists() or owned(path, path.parent)  # Lipspace's corpus: its audio folder is too
    try:
        with_audio = add_speech_audio(corpus, folder, progress=progress)
        if made:
            mark(folder, path.parent)
        return with_audio
    except SpeechAudioUnavailable as exc:
        corpus.history.append(f"speech audio: none; {exc}")
    except (OSError, ValueError, subprocess.SubprocessError) as exc:
        corpus.history.append(f"speech audio: none; generating it failed ({exc})")
    return corpus
