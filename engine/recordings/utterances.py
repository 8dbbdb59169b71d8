"""The records of a corpus: utterances, their phone intervals, and the corpus's errors and warnings.

An :class:`Utterance` is a contiguous frame range of a :class:`~engine.recordings.corpus.Corpus`
with its phone alignment (:class:`PhoneInterval`, seconds from the utterance start), its audio,
text, speaker and metadata fields. :func:`label_codes` and :func:`frame_points` are the small
conversions every reader of a corpus's phones and frames uses.
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["CorpusError", "CorpusWarning", "PhoneInterval", "Utterance", "label_codes", "frame_points"]


class CorpusError(ValueError):
    """Raised when corpus data is malformed; the message names what and where."""


class CorpusWarning(UserWarning):
    """Something about the user's data that the results depend on; the work goes on.

    Base class of the engine's warnings about data (e.g. a disconnected state graph).
    The command line prints them as one plain line and the window shows them in its
    status bar.
    """


@dataclass(frozen=True)
class PhoneInterval:
    """One phone of an alignment, times in seconds from the utterance start."""

    start: float
    end: float
    label: str

    @property
    def mid(self) -> float:
        return 0.5 * (self.start + self.end)

    @classmethod
    def _many(cls, times: Sequence[tuple[float, float]], labels: Sequence[str]) -> tuple[PhoneInterval, ...]:
        """Phones from lists of ``(start, end)`` floats and ``str`` labels (already of those types, as
        ``tolist()`` of a file's float and str arrays gives them), without the dataclass's per-field
        ``__init__`` (a million-frame corpus has ~10^5 phones). :meth:`Corpus.validate` checks them."""
        new = object.__new__
        out = []
        for (t0, t1), lab in zip(times, labels):
            p = new(cls)
            p.__dict__.update(start=t0, end=t1, label=lab)
            out.append(p)
        return _Phones(out)


class _Phones(tuple):
    """A tuple of PhoneInterval built by :meth:`PhoneInterval._many`: a corpus keeps it as it is."""

    __slots__ = ()


@dataclass(frozen=True)
class Utterance:
    """A contiguous frame range ``[start, stop)`` of the corpus.

    Parameters
    ----------
    id : str
        Unique name of the utterance.
    start, stop : int
        Frame range in the corpus (``stop`` exclusive).
    phones : tuple of PhoneInterval
        Sorted, non-overlapping phone intervals, seconds from the utterance start.
    audio : str or None
        Path of a WAV file holding the utterance's audio, if any.
    text : str
        Orthographic text, if known.
    speaker : str
        Who spoke it ("" = unknown). Multi-speaker corpora are normalised per speaker
        before the shape space (:mod:`engine.recordings.registration`).
    duration_s : float
        How long the recording lasts (s) when that is known more finely than its frames: an
        utterance resampled from n frames at r Hz lasts n / r, which its frames at the new rate
        round up (:func:`engine.io.resample`). 0: ``n_frames / rate``.
    fields : tuple of (str, str)
        Other metadata fields, ``(name, value)`` in order (sex, emotion, text number,
        session, group ...; :mod:`engine.recordings.metadata` reads them).
    words : tuple of PhoneInterval
        The word tier where the source has one (a Haskins file's ``WORDS``), seconds from
        the utterance start, labels as given; () when the source has none.
    """

    id: str
    start: int
    stop: int
    phones: tuple[PhoneInterval, ...] = ()
    audio: str | None = None
    text: str = ""
    speaker: str = ""
    duration_s: float = 0.0
    fields: tuple[tuple[str, str], ...] = ()
    words: tuple = ()

    @property
    def n_frames(self) -> int:
        return self.stop - self.start


def _as_phones(phones: Iterable[Any]) -> tuple[PhoneInterval, ...]:
    if type(phones) is _Phones:
        return phones  # a file's phones (PhoneInterval._many): kept, not rebuilt
    if type(phones) is tuple and all(type(p) is PhoneInterval for p in phones):
        return phones  # already phones: kept
    out = []
    for p in phones:
        if isinstance(p, PhoneInterval):
            out.append(p)
        else:
            s, e, lab = p
            out.append(PhoneInterval(float(s), float(e), str(lab)))
    return tuple(out)



def label_codes(labels: Iterable[str] | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(np.asarray(labels, dtype=str), return_inverse=True)`` by hashing, not sorting strings.

    Parameters
    ----------
    labels : sequence of str or ndarray of str, shape (n,)

    Returns
    -------
    names : ndarray of str, sorted distinct labels
    inverse : ndarray of shape (n,) int64, ``names[inverse] == labels``
    """
    seq = labels.tolist() if isinstance(labels, np.ndarray) else [str(x) for x in labels]
    names = sorted(set(seq))  # code-point order, as numpy sorts strings
    pos = {x: i for i, x in enumerate(names)}
    inverse = np.fromiter(map(pos.__getitem__, seq), np.int64, count=len(seq))
    return np.array(names, dtype=str), inverse



def frame_points(row: np.ndarray, dims: int) -> np.ndarray:
    """Reshape one frame (or (n, dims*V) frames) to points with 3 coordinates (z = 0 for 2-D)."""
    row = np.asarray(row)
    pts = row.reshape(*row.shape[:-1], -1, dims)
    if dims == 2:
        pts = np.concatenate([pts, np.zeros(pts.shape[:-1] + (1,), pts.dtype)], axis=-1)
    return pts
