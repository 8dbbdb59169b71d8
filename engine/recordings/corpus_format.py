"""The corpus's file format: a flat dict of arrays (no pickled objects), and the ``.npz`` file holding it.

:func:`corpus_to_arrays` and :func:`corpus_from_arrays` turn a corpus into the arrays and back
(``corpus_*`` keys, checked by :func:`engine.files.validate.check_corpus_arrays` before anything
is built from them); :func:`save_corpus` writes them atomically and :func:`load_corpus` reads them,
naming the file in every error. Audio paths are stored relative to the file's folder and
absolute beside them, so a folder moved with its sound keeps it and a corpus file moved on its
own still finds it. :meth:`Corpus.to_arrays <engine.recordings.corpus.Corpus.to_arrays>` and its
siblings call these.
"""
from __future__ import annotations

import gc
import os
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from engine.files.atomic import atomic_write
from engine.recordings.utterances import CorpusError, PhoneInterval, Utterance

__all__ = ["FORMAT_VERSION", "corpus_to_arrays", "corpus_from_arrays", "save_corpus", "load_corpus"]

#: the version of the corpus arrays this code writes (files of a newer one are refused)
FORMAT_VERSION = 1

_C = TypeVar("_C")


def corpus_to_arrays(corpus: Any, *, include_frames: bool = True,
                     base: str | os.PathLike[str] | None = None) -> dict[str, np.ndarray]:
    """Flat dict of arrays for ``np.savez`` (no pickled objects).

    ``base``: the folder of the file the arrays go to. Audio paths are then stored
    relative to it (``corpus_utt_audio``), so a folder moved with its sound keeps it, and
    absolute as well (``corpus_utt_audio_abs``), for a corpus file moved on its own.
    """
    phones = [(k, p.start, p.end, p.label) for k, u in enumerate(corpus.utterances) for p in u.phones]
    d = {
        "corpus_version": np.array(FORMAT_VERSION),
        "corpus_rate": np.array(corpus.rate),
        "corpus_dims": np.array(corpus.dims),
        "corpus_name": np.array(corpus.name),
        "corpus_n_frames": np.array(corpus.n_frames),
        "corpus_n_columns": np.array(corpus.frames.shape[1]),
        "corpus_utt_ids": np.array([u.id for u in corpus.utterances], dtype=str),
        "corpus_utt_bounds": corpus.bounds,
        "corpus_utt_audio": np.array([_relative(u.audio, base) for u in corpus.utterances], dtype=str),
        "corpus_utt_text": np.array([u.text for u in corpus.utterances], dtype=str),
        "corpus_utt_speaker": np.array([u.speaker for u in corpus.utterances], dtype=str),
        "corpus_registration": np.array(corpus.registration),
        "corpus_history": np.array(corpus.history, dtype=str).reshape(-1),
        "corpus_phone_utt": np.array([p[0] for p in phones], dtype=np.int64),
        "corpus_phone_times": np.array([[p[1], p[2]] for p in phones], dtype=np.float64).reshape(-1, 2),
        "corpus_phone_labels": np.array([p[3] for p in phones], dtype=str),
    }
    words = [(k, w.start, w.end, w.label) for k, u in enumerate(corpus.utterances) for w in u.words]
    if any(u.duration_s for u in corpus.utterances):  # resampled recordings' true durations (else as before)
        d["corpus_utt_duration"] = np.array([float(u.duration_s) for u in corpus.utterances], dtype=np.float64)
    if words:  # the word tiers, where the source had them (files without them read as before)
        d["corpus_word_utt"] = np.array([w[0] for w in words], dtype=np.int64)
        d["corpus_word_times"] = np.array([[w[1], w[2]] for w in words], dtype=np.float64).reshape(-1, 2)
        d["corpus_word_labels"] = np.array([w[3] for w in words], dtype=str)
    if include_frames:
        d["corpus_frames"] = corpus.frames
    if corpus.faces is not None:
        d["corpus_faces"] = corpus.faces
    if corpus.point_names is not None:
        d["corpus_point_names"] = np.array(corpus.point_names, dtype=str)
    if corpus.point_roles is not None:
        d["corpus_point_roles"] = np.array(corpus.point_roles, dtype=str)
    if corpus.axes:
        d["corpus_axes"] = np.array(corpus.axes)
    d["corpus_units"] = np.array(corpus.units)
    from engine.recordings.field_arrays import fields_to_arrays

    d.update(fields_to_arrays(corpus.utterances))
    if base is not None:
        d["corpus_utt_audio_abs"] = np.array([_absolute(u.audio) for u in corpus.utterances], dtype=str)
    for k, v in corpus.latent.items():
        d[f"corpus_latent_{k}"] = v
    return d

def corpus_from_arrays(cls: Callable[..., _C], d: Mapping[str, Any], *, frames: Any = None,
                       source: str = "<arrays>", base: str | os.PathLike[str] | None = None) -> _C:
    """Inverse of :func:`corpus_to_arrays`: a corpus of class ``cls``; ``frames`` overrides the stored frames.

    ``base``: the folder of the file read. A relative audio path is taken relative to it
    (made absolute); when that file is missing and the absolute path stored beside it
    exists, that one. Absolute paths (files written before) are kept.
    """
    from engine.files.validate import FieldError, check_corpus_arrays
    from engine.recordings.field_arrays import fields_from_arrays

    try:  # dtypes, shapes and index ranges checked before anything is built from them
        check_corpus_arrays(d, source=source, frames_given=frames is not None)
        fields = fields_from_arrays(d, len(d["corpus_utt_ids"]), source=source)
    except FieldError as exc:
        raise CorpusError(str(exc)) from None
    try:
        version = int(d["corpus_version"])
        if version > FORMAT_VERSION:
            raise CorpusError(f"{source}: corpus format {version} is newer than this Lipspace ({FORMAT_VERSION})")
        if frames is None:
            frames = d["corpus_frames"]
        bounds = d["corpus_utt_bounds"]
        ids = d["corpus_utt_ids"]
        audio = d["corpus_utt_audio"]
        text = d["corpus_utt_text"]
        p_utt = d["corpus_phone_utt"]
        p_t = d["corpus_phone_times"]
        p_lab = d["corpus_phone_labels"]
        keys = list(d.keys())
        latent = {k[len("corpus_latent_"):]: d[k] for k in keys if k.startswith("corpus_latent_")}
        faces = d["corpus_faces"] if "corpus_faces" in keys else None
        names = list(d["corpus_point_names"]) if "corpus_point_names" in keys else None
        roles = list(d["corpus_point_roles"]) if "corpus_point_roles" in keys else None
        speaker = d["corpus_utt_speaker"] if "corpus_utt_speaker" in keys else [""] * len(ids)
        duration = d["corpus_utt_duration"] if "corpus_utt_duration" in keys else np.zeros(len(ids))
        registration = str(d["corpus_registration"]) if "corpus_registration" in keys else ""
        history = [str(h) for h in d["corpus_history"]] if "corpus_history" in keys else []
        axes = str(d["corpus_axes"]) if "corpus_axes" in keys else ""
        units = str(d["corpus_units"]) if "corpus_units" in keys else ""  # older files did not say
        audio_abs = d["corpus_utt_audio_abs"] if "corpus_utt_audio_abs" in keys else None
        words = _words_of(d, len(ids)) if "corpus_word_utt" in keys else None
        rate, dims, name = float(d["corpus_rate"]), int(d["corpus_dims"]), str(d["corpus_name"])
    except KeyError as exc:
        raise CorpusError(f"{source}: not a Lipspace corpus file (missing {exc.args[0]!r})") from None
    utts = []
    # each utterance's phones in file order, found by one sort (not a scan of every phone per utterance)
    by_utt = np.argsort(np.asarray(p_utt), kind="stable")
    cuts = np.searchsorted(np.asarray(p_utt)[by_utt], np.arange(len(ids) + 1))
    with _collection_paused():
        times, labels = _as_list(np.asarray(p_t)[by_utt]), _as_list(np.asarray(p_lab)[by_utt])
        for k, (b, uid) in enumerate(zip(bounds.tolist(), ids.tolist())):
            a, e = int(cuts[k]), int(cuts[k + 1])
            phones = PhoneInterval._many(times[a:e], labels[a:e])
            wav = _resolve(str(audio[k]), base, str(audio_abs[k]) if audio_abs is not None else "")
            utts.append(Utterance(str(uid), int(b[0]), int(b[1]), phones, wav, str(text[k]), str(speaker[k]),
                                  float(duration[k]),
                                  fields=fields[k] if fields is not None else (),
                                  words=words[k] if words is not None else ()))
    try:
        return cls(frames=frames, rate=rate, utterances=utts, dims=dims, faces=faces, point_names=names,
                   latent=latent, name=name, point_roles=roles, registration=registration, history=history,
                   axes=axes, units=units)
    except CorpusError as exc:  # name the file, not only the corpus
        raise CorpusError(f"{source}: {exc}") from None

def save_corpus(corpus: Any, path: str | os.PathLike[str]) -> Path:
    """Write the native corpus file (``.npz``) atomically."""
    path = Path(path)
    with atomic_write(path) as tmp:
        with open(tmp, "wb") as fh:
            arrays = corpus_to_arrays(corpus, base=path.resolve().parent)
            np.savez(fh, **arrays)  # type: ignore[arg-type]  # numpy types only the positional arrays
    return path

def load_corpus(cls: Callable[..., _C], path: str | os.PathLike[str]) -> _C:
    """Read a native corpus file written by :func:`save_corpus`, as a corpus of class ``cls``."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such corpus file")
    from engine.files.persist import NpzReadError, read_npz

    try:
        return corpus_from_arrays(cls, read_npz(path), source=str(path), base=path.resolve().parent)
    except CorpusError:
        raise
    except NpzReadError as exc:
        reason = exc.reason
    except Exception as exc:  # arrays of the wrong shape or type
        reason = f"its arrays do not form a corpus ({exc})"
    raise CorpusError(f"{path}: cannot read as a Lipspace corpus (.npz): {reason}")


@contextmanager
def _collection_paused() -> Iterator[None]:
    """Python's cyclic garbage collector off while a file's phones become objects.

    Each full collection walks every tracked object, and 1.6 million phones (ten million
    frames) set several off, each holding the GIL -- and so the window's event loop, when a
    worker thread loads -- for 0.3-0.7 s. Nothing built here forms a cycle.
    """
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def _as_list(a: np.ndarray, chunk: int = 1 << 16) -> list[Any]:
    """``a.tolist()`` a block of rows at a time: one call over a million rows holds the GIL for a second."""
    out = []
    for s in range(0, len(a), chunk):
        out.extend(a[s:s + chunk].tolist())
    return out


def _words_of(d: Mapping[str, Any], n_utterances: int) -> list[tuple[PhoneInterval, ...]]:
    """Each utterance's word tier from a file's ``corpus_word_*`` arrays."""
    utt = np.asarray(d["corpus_word_utt"], dtype=np.int64).reshape(-1)
    times = np.asarray(d["corpus_word_times"], dtype=np.float64).reshape(-1, 2)
    labels = np.asarray(d["corpus_word_labels"]).reshape(-1)
    if not (len(utt) == len(times) == len(labels)) or (len(utt) and (utt.min() < 0 or utt.max() >= n_utterances)):
        raise CorpusError(f"word tiers: {len(utt)} utterance indices, {len(times)} times, {len(labels)} labels "
                          f"for {n_utterances} utterances; expected one of each per word, indices in range")
    out: list[list] = [[] for _ in range(n_utterances)]
    for k, (t0, t1), lab in zip(utt.tolist(), times.tolist(), labels.tolist()):
        out[k].append(PhoneInterval(float(t0), float(t1), str(lab)))
    return [tuple(w) for w in out]




def _absolute(audio: str | os.PathLike[str] | None) -> str:
    """An audio path made absolute ("" for none), symlinks kept."""
    import os

    return os.path.abspath(audio) if audio else ""


def _relative(audio: str | None, base: str | os.PathLike[str] | None) -> str:
    """An audio path as stored: relative to ``base`` when given (and on the same drive), else as it is."""
    import os

    if not audio or base is None:
        return audio or ""
    try:
        return os.path.relpath(os.path.abspath(audio), os.path.abspath(base))
    except ValueError:  # another drive (Windows): no relative path exists
        return _absolute(audio)


def _resolve(stored: str, base: str | os.PathLike[str] | None, absolute: str) -> str | None:
    """The audio path a stored one means (see :func:`corpus_from_arrays`); None for none."""
    import os

    if not stored:
        return None
    if os.path.isabs(stored) or base is None:
        return stored
    p = os.path.normpath(os.path.join(str(base), stored))
    if not os.path.isfile(p) and absolute and os.path.isfile(absolute):
        return absolute  # the corpus file was moved without its sound
    return p


