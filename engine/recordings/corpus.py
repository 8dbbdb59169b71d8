"""The corpus: frames of lip geometry, utterances and their phone alignments.

A :class:`Corpus` is the input to everything in the engine. Frames never connect
across utterance boundaries: no velocity, transition or path crosses one.
"""
from __future__ import annotations

import gc
import math
import os
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from engine.files.atomic import atomic_write
from engine.recordings.frame_blocks import BlockFrames

__all__ = ["CorpusError", "CorpusWarning", "PhoneInterval", "Utterance", "Corpus", "label_codes"]

FORMAT_VERSION = 1
#: largest coordinate magnitude a corpus holds (the importers treat larger samples as dropouts)
MAX_COORDINATE = 1e6


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


@dataclass
class Corpus:
    """Frames of lip geometry with utterances and phone alignments.

    Parameters
    ----------
    frames : ndarray of shape (n_frames, dims * n_points)
        One row per frame, coordinates interleaved per point (x0, y0, z0, x1, ...).
        Stored as float32.
    rate : float
        Frame rate in Hz (the paper: 60).
    utterances : sequence of Utterance
        Contiguous, non-overlapping frame ranges covering the frames in order.
    dims : {2, 3}
        Coordinates per point.
    faces : ndarray of shape (n_faces, 3) or None
        Triangles over the points, for drawing a mesh.
    point_names : sequence of str or None
        One name per point (markers, sensors).
    latent : dict of str to ndarray of shape (n_frames,)
        Ground-truth per-frame signals (the synthetic talker's articulatory controls).
    name : str
        Human-readable name of the corpus.
    point_roles : sequence of str or None
        One role per point from :data:`engine.recordings.layouts.ROLES` ("" = none): which points
        are upper / lower lip, mouth corners, jaw, reference (head) or tongue sensors.
        With upper and lower lip known, "opening" means the lip aperture grows.
    registration : str
        How head motion / position was removed, in words ("" = none was applied).
    history : list of str
        Processing steps applied on import (resampling, registration, ...), in order.
    units : str
        Unit of the coordinates ("mm" for articulographs, video and the synthetic talker;
        "" = the file's own, unknown: meshes, generic CSV tracks, C3D without units).
    axes : str
        The talker's directions of the coordinate axes when stated on import
        (``lipspace import --axes x=forward,y=left,z=up``); "" = derived from the point
        roles (:func:`engine.recordings.orientation.anatomical_frame`).
    """

    frames: np.ndarray
    rate: float
    utterances: list[Utterance]
    dims: int = 3
    faces: np.ndarray | None = None
    point_names: list[str] | None = None
    latent: dict[str, np.ndarray] = field(default_factory=dict)
    name: str = "corpus"
    point_roles: list[str] | None = None
    registration: str = ""
    history: list[str] = field(default_factory=list)
    axes: str = ""
    units: str = "mm"

    def __post_init__(self) -> None:
        if not isinstance(self.frames, BlockFrames):  # frames stored in blocks stay there (engine.recordings.frame_blocks)
            self.frames = np.asarray(self.frames, dtype=np.float32)
        self.utterances = [u if (ph := _as_phones(u.phones)) is u.phones else replace(u, phones=ph)
                           for u in self.utterances]
        self.rate = float(self.rate)
        if self.faces is not None:
            self.faces = np.asarray(self.faces, dtype=np.int64)
        if self.point_names is not None:
            self.point_names = [str(n) for n in self.point_names]
        if self.point_roles is not None:
            self.point_roles = [str(r) for r in self.point_roles]
        self.registration = str(self.registration)
        self.history = [str(h) for h in self.history]
        self.axes = str(self.axes)
        self.units = str(self.units)
        self.latent = {k: np.asarray(v) for k, v in self.latent.items()}
        self.validate()

    # ------------------------------------------------------------------ checks
    def validate(self) -> None:
        """Check every invariant; raise :class:`CorpusError` naming the fault."""
        F = self.frames
        if F.ndim != 2:
            raise CorpusError(f"{self.name}: frames must be 2-D (n_frames, dims*n_points), got shape {F.shape}")
        if self.dims not in (2, 3):
            raise CorpusError(f"{self.name}: dims must be 2 or 3, got {self.dims}")
        if F.shape[1] == 0 or F.shape[1] % self.dims:
            raise CorpusError(
                f"{self.name}: frames have {F.shape[1]} columns, not a positive multiple of dims={self.dims}"
            )
        if F.shape[0] < 2:
            raise CorpusError(f"{self.name}: need at least 2 frames, got {F.shape[0]}")
        if not np.isfinite(self.rate) or self.rate <= 0:
            raise CorpusError(f"{self.name}: rate must be a positive number of Hz, got {self.rate}")
        # frames stored in blocks are checked where they are read (the shape stage), not gathered here;
        # the extremes first (NaN and inf show in them), so that finite frames cost two passes, no copy
        blocked = isinstance(F, BlockFrames)
        lo, hi = (0.0, 0.0) if blocked or not F.size else (float(F.min()), float(F.max()))
        bad = ~np.isfinite(F) if not (np.isfinite(lo) and np.isfinite(hi)) else np.zeros((0, 0), bool)
        if bad.any():
            i, j = np.argwhere(bad)[0]
            raise CorpusError(
                f"{self.name}: frame {i} column {j} is {F[i, j]} (NaN/inf); "
                f"{int(bad.any(axis=1).sum())} frames are not finite. Interpolate or drop them before building."
            )
        if not blocked and F.size and max(-lo, hi) > MAX_COORDINATE:
            i, j = np.argwhere(np.abs(F) > MAX_COORDINATE)[0]
            raise CorpusError(
                f"{self.name}: frame {i} column {j} is {F[i, j]:g}; coordinates beyond {MAX_COORDINATE:g} (in any "
                "unit lips are measured in) are a damaged sample or wrong units. Import the recording again "
                "(lipspace import treats them as dropouts)")
        if not self.utterances:
            raise CorpusError(f"{self.name}: no utterances; every frame must belong to one")
        expected = 0
        seen = set()
        for u in self.utterances:
            if u.id in seen:
                raise CorpusError(f"{self.name}: utterance id {u.id!r} appears twice")
            seen.add(u.id)
            if u.stop <= u.start:
                raise CorpusError(f"{self.name}: utterance {u.id!r} is empty (frames {u.start}..{u.stop})")
            if u.start != expected:
                raise CorpusError(
                    f"{self.name}: utterance {u.id!r} starts at frame {u.start}, expected {expected} "
                    "(utterances must be contiguous, in order, covering all frames)"
                )
            expected = u.stop
        self._validate_phones()
        if expected != F.shape[0]:
            raise CorpusError(
                f"{self.name}: utterances cover {expected} frames but frames has {F.shape[0]} rows"
            )
        if self.faces is not None:
            f = self.faces
            if f.ndim != 2 or f.shape[1] != 3:
                raise CorpusError(f"{self.name}: faces must be (n_faces, 3), got {f.shape}")
            if f.size and (f.min() < 0 or f.max() >= self.n_points):
                raise CorpusError(
                    f"{self.name}: faces index points {f.min()}..{f.max()} but there are {self.n_points} points"
                )
        if self.point_names is not None and len(self.point_names) != self.n_points:
            raise CorpusError(
                f"{self.name}: {len(self.point_names)} point names for {self.n_points} points"
            )
        if self.point_names is not None and len(set(self.point_names)) != len(self.point_names):
            first: dict[str, int] = {}
            for k, n in enumerate(self.point_names):  # which point is which cannot be told: refused, not guessed
                if n in first:
                    raise CorpusError(f"{self.name}: points {first[n] + 1} and {k + 1} are both named {n!r}; "
                                      "expected one name per point")
                first[n] = k
        if self.axes:
            from engine.recordings.orientation import AxesError, parse_axes

            try:
                parse_axes(self.axes, self.dims)
            except AxesError as exc:
                raise CorpusError(f"{self.name}: its axes {self.axes!r} are damaged: "
                                  f"{str(exc).split(': ', 1)[-1]}") from None
        if self.point_roles is not None:
            if len(self.point_roles) != self.n_points:
                raise CorpusError(f"{self.name}: {len(self.point_roles)} point roles for {self.n_points} points")
            from engine.recordings.layouts import ROLES

            bad_roles = sorted({r for r in self.point_roles if r and r not in ROLES})
            if bad_roles:
                raise CorpusError(f"{self.name}: unknown point role(s) {bad_roles}; expected one of {list(ROLES)}")
        for key, v in self.latent.items():
            if v.shape[0] != F.shape[0]:
                raise CorpusError(f"{self.name}: latent {key!r} has {v.shape[0]} rows, frames have {F.shape[0]}")

    def _validate_phones(self) -> None:
        """Every phone's checks at once (a ten-million-frame corpus has 1.6 million phones); the first
        utterance with a faulty phone is then checked phone by phone for the message."""
        from itertools import chain
        from operator import attrgetter

        per_utt = [u.phones for u in self.utterances]
        counts = np.fromiter(map(len, per_utt), np.int64, count=len(per_utt))
        n = int(counts.sum())
        if n == 0:
            return
        flat = list(chain.from_iterable(per_utt))
        s = np.fromiter(map(attrgetter("start"), flat), np.float64, count=n)
        e = np.fromiter(map(attrgetter("end"), flat), np.float64, count=n)
        labelled = np.fromiter(map(bool, map(attrgetter("label"), flat)), bool, count=n)
        utt = np.repeat(np.arange(len(per_utt)), counts)
        dur = (self.bounds @ np.array([-1, 1]))[utt] / self.rate
        prev = np.r_[-np.inf, e[:-1]]
        prev[np.r_[0, np.cumsum(counts)[:-1]][counts > 0]] = -np.inf  # an utterance's first phone
        with np.errstate(invalid="ignore"):
            ok = (np.isfinite(s) & np.isfinite(e) & labelled & (e > s) & (s >= prev - 1e-9) & (s >= -1e-9)
                  & (e <= dur + (0.5 / self.rate + 1e-9)))
        if not ok.all():
            u = self.utterances[int(utt[np.argmin(ok)])]
            self._check_phones(u)  # raises, naming the phone
            raise CorpusError(f"{self.name}: utterance {u.id!r} has a phone that fails the checks")

    def _check_phones(self, u: Utterance) -> None:
        """Raise CorpusError naming the first faulty phone of ``u``."""
        dur = u.n_frames / self.rate
        prev_end = -np.inf
        tol = 0.5 / self.rate + 1e-9
        for k, p in enumerate(u.phones):
            if not (math.isfinite(p.start) and math.isfinite(p.end)):
                raise CorpusError(f"{self._where(u, k, p)}: times must be finite")
            if not p.label:
                raise CorpusError(f"{self._where(u, k, p)}: empty label")
            if p.end <= p.start:
                raise CorpusError(f"{self._where(u, k, p)}: end is not after start")
            if p.start < prev_end - 1e-9:
                raise CorpusError(
                    f"{self._where(u, k, p)}: starts before the previous phone ends at {prev_end:.4f} s "
                    "(intervals must be sorted and not overlap)"
                )
            if p.start < -1e-9 or p.end > dur + tol:
                raise CorpusError(
                    f"{self._where(u, k, p)}: lies outside the utterance (0-{dur:.4f} s, {u.n_frames} frames "
                    f"at {self.rate:g} Hz)"
                )
            prev_end = p.end

    def _where(self, u: Utterance, k: int, p: PhoneInterval) -> str:
        return f"{self.name}: utterance {u.id!r} phone {k} ({p.label!r} {p.start:.4f}-{p.end:.4f} s)"

    # -------------------------------------------------------------- properties
    @property
    def n_frames(self) -> int:
        return self.frames.shape[0]

    @property
    def n_points(self) -> int:
        return self.frames.shape[1] // self.dims

    @property
    def bounds(self) -> np.ndarray:
        """Utterance frame ranges, ndarray of shape (n_utterances, 2): ``[start, stop)``.

        Read attribute by attribute into arrays: a list per utterance would be a container the
        cyclic collector counts, and at 10M frames (49,000 utterances) those set off a full
        collection over every phone object."""
        from operator import attrgetter

        utts = self.utterances
        return np.column_stack([np.fromiter(map(attrgetter(k), utts), np.int64, count=len(utts))
                                for k in ("start", "stop")]).reshape(-1, 2)

    @property
    def utterance_index(self) -> np.ndarray:
        """Utterance number of every frame, ndarray of shape (n_frames,)."""
        b = self.bounds
        return np.repeat(np.arange(len(b)), b[:, 1] - b[:, 0])

    @property
    def duration(self) -> float:
        return self.n_frames / self.rate

    @property
    def unit_label(self) -> str:
        """The coordinates' unit for messages and axis labels: :attr:`units`, or "data units" when unknown."""
        return self.units or "data units"

    @property
    def speakers(self) -> list[str]:
        """Distinct speakers in utterance order ("" = unknown)."""
        return list(dict.fromkeys(u.speaker for u in self.utterances))

    def role_points(self, role: str) -> np.ndarray:
        """Indices of the points with ``role`` (empty when roles are unknown)."""
        if self.point_roles is None:
            return np.zeros(0, np.int64)
        return np.array([i for i, r in enumerate(self.point_roles) if r == role], dtype=np.int64)

    def utterance(self, uid: str) -> Utterance:
        """The utterance named ``uid`` (KeyError naming a few known ones if none is).

        Found through an id -> position table kept beside ``utterances`` (a scan of every
        utterance took milliseconds per lookup at ten million frames); a position whose
        utterance no longer has that id (the list was changed) rebuilds the table.
        """
        table: Any = self.__dict__.get("_positions")
        for rebuild in (table is None or table[0] is not self.utterances, True):
            if rebuild:
                table = (self.utterances, {u.id: i for i, u in enumerate(self.utterances)})
                self.__dict__["_positions"] = table
            i = table[1].get(uid)
            if i is not None and i < len(self.utterances) and self.utterances[i].id == uid:
                return self.utterances[i]
            if rebuild:
                break  # a table just built has no such id
        raise KeyError(f"no utterance {uid!r} in {self.name}; known: {[u.id for u in self.utterances[:5]]}...")

    def points(self, i: int) -> np.ndarray:
        """Frame ``i`` as points, ndarray of shape (n_points, 3) (z = 0 for 2-D data)."""
        return frame_points(self.frames[i], self.dims)

    def time_to_frame(self, u: Utterance, t: float) -> int:
        """Corpus frame index nearest to time ``t`` (s) inside utterance ``u``, clipped to it."""
        return int(np.clip(u.start + int(round(t * self.rate)), u.start, u.stop - 1))

    def phone_table(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """All phones with their mid-point frames.

        Returns
        -------
        mid_frames : ndarray of shape (n_phones,) int
        labels : ndarray of shape (n_phones,) str
        utterance : ndarray of shape (n_phones,) int, utterance number
        start_frames, end_frames : ndarray of shape (n_phones,) int

        The arrays are read-only and kept while the utterances are the same objects (they and
        their phones are frozen), so the views' several readers build them once.
        """
        from itertools import chain
        from operator import attrgetter

        kept = self.__dict__.get("_phone_table")  # (rate, the utterance objects, the table)
        if (kept is not None and kept[0] == self.rate and len(kept[1]) == len(self.utterances)
                and all(a is b for a, b in zip(kept[1], self.utterances))):
            return kept[2]
        per_utt = [u.phones for u in self.utterances]
        flat = list(chain.from_iterable(per_utt))
        utt = np.repeat(np.arange(len(per_utt), dtype=np.int64),
                        np.fromiter(map(len, per_utt), np.int64, count=len(per_utt)))
        times = np.column_stack([np.fromiter(map(attrgetter(k), flat), np.float64, count=len(flat))
                                 for k in ("start", "end")])
        labs = np.array(list(map(attrgetter("label"), flat)), dtype=str)
        b = self.bounds
        lo, hi = b[utt, 0], b[utt, 1] - 1

        # time_to_frame, for every phone at once (np.rint rounds half to even, as round)
        def frame(t: np.ndarray) -> np.ndarray:
            return np.clip(lo + np.rint(t * self.rate).astype(np.int64), lo, hi)

        table = (frame(times.sum(axis=1) * 0.5), labs, utt, frame(times[:, 0]), frame(times[:, 1]))
        for a in table:
            a.flags.writeable = False
        self.__dict__["_phone_table"] = (self.rate, tuple(self.utterances), table)
        return table

    def subset(self, ids: Iterable[str]) -> Corpus:
        """A new corpus holding only the utterances named in ``ids`` (in corpus order)."""
        ids = set(ids)
        keep = [u for u in self.utterances if u.id in ids]
        if not keep:
            raise CorpusError(f"{self.name}: none of the utterances {sorted(ids)[:5]} exist")
        rows = np.concatenate([np.arange(u.start, u.stop) for u in keep])
        out, pos = [], 0
        for u in keep:
            out.append(replace(u, start=pos, stop=pos + u.n_frames))
            pos += u.n_frames
        return Corpus(
            frames=self.frames[rows], rate=self.rate, utterances=out, dims=self.dims, faces=self.faces,
            point_names=self.point_names, latent={k: v[rows] for k, v in self.latent.items()}, name=self.name,
            point_roles=self.point_roles, registration=self.registration, history=list(self.history),
            axes=self.axes, units=self.units,
        )

    # -------------------------------------------------------------- file i/o
    def to_arrays(self, *, include_frames: bool = True,
                  base: str | os.PathLike[str] | None = None) -> dict[str, np.ndarray]:
        """Flat dict of arrays for ``np.savez`` (no pickled objects).

        ``base``: the folder of the file the arrays go to. Audio paths are then stored
        relative to it (``corpus_utt_audio``), so a folder moved with its sound keeps it, and
        absolute as well (``corpus_utt_audio_abs``), for a corpus file moved on its own.
        """
        phones = [(k, p.start, p.end, p.label) for k, u in enumerate(self.utterances) for p in u.phones]
        d = {
            "corpus_version": np.array(FORMAT_VERSION),
            "corpus_rate": np.array(self.rate),
            "corpus_dims": np.array(self.dims),
            "corpus_name": np.array(self.name),
            "corpus_n_frames": np.array(self.n_frames),
            "corpus_n_columns": np.array(self.frames.shape[1]),
            "corpus_utt_ids": np.array([u.id for u in self.utterances], dtype=str),
            "corpus_utt_bounds": self.bounds,
            "corpus_utt_audio": np.array([_relative(u.audio, base) for u in self.utterances], dtype=str),
            "corpus_utt_text": np.array([u.text for u in self.utterances], dtype=str),
            "corpus_utt_speaker": np.array([u.speaker for u in self.utterances], dtype=str),
            "corpus_registration": np.array(self.registration),
            "corpus_history": np.array(self.history, dtype=str).reshape(-1),
            "corpus_phone_utt": np.array([p[0] for p in phones], dtype=np.int64),
            "corpus_phone_times": np.array([[p[1], p[2]] for p in phones], dtype=np.float64).reshape(-1, 2),
            "corpus_phone_labels": np.array([p[3] for p in phones], dtype=str),
        }
        words = [(k, w.start, w.end, w.label) for k, u in enumerate(self.utterances) for w in u.words]
        if any(u.duration_s for u in self.utterances):  # resampled recordings' true durations (else as before)
            d["corpus_utt_duration"] = np.array([float(u.duration_s) for u in self.utterances], dtype=np.float64)
        if words:  # the word tiers, where the source had them (files without them read as before)
            d["corpus_word_utt"] = np.array([w[0] for w in words], dtype=np.int64)
            d["corpus_word_times"] = np.array([[w[1], w[2]] for w in words], dtype=np.float64).reshape(-1, 2)
            d["corpus_word_labels"] = np.array([w[3] for w in words], dtype=str)
        if include_frames:
            d["corpus_frames"] = self.frames
        if self.faces is not None:
            d["corpus_faces"] = self.faces
        if self.point_names is not None:
            d["corpus_point_names"] = np.array(self.point_names, dtype=str)
        if self.point_roles is not None:
            d["corpus_point_roles"] = np.array(self.point_roles, dtype=str)
        if self.axes:
            d["corpus_axes"] = np.array(self.axes)
        d["corpus_units"] = np.array(self.units)
        from engine.recordings.field_arrays import fields_to_arrays

        d.update(fields_to_arrays(self.utterances))
        if base is not None:
            d["corpus_utt_audio_abs"] = np.array([_absolute(u.audio) for u in self.utterances], dtype=str)
        for k, v in self.latent.items():
            d[f"corpus_latent_{k}"] = v
        return d

    @classmethod
    def from_arrays(cls, d: Mapping[str, Any], *, frames: Any = None, source: str = "<arrays>",
                    base: str | os.PathLike[str] | None = None) -> Corpus:
        """Inverse of :meth:`to_arrays`; ``frames`` overrides the stored frames.

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

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the native corpus file (``.npz``) atomically."""
        path = Path(path)
        with atomic_write(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, **self.to_arrays(base=path.resolve().parent))  # type: ignore[arg-type]  # numpy types only the positional arrays
        return path

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Corpus:
        """Read a native corpus file written by :meth:`save`."""
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(f"{path}: no such corpus file")
        from engine.files.persist import NpzReadError, read_npz

        try:
            return cls.from_arrays(read_npz(path), source=str(path), base=path.resolve().parent)
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
    """The audio path a stored one means (see :meth:`Corpus.from_arrays`); None for none."""
    import os

    if not stored:
        return None
    if os.path.isabs(stored) or base is None:
        return stored
    p = os.path.normpath(os.path.join(str(base), stored))
    if not os.path.isfile(p) and absolute and os.path.isfile(absolute):
        return absolute  # the corpus file was moved without its sound
    return p


def frame_points(row: np.ndarray, dims: int) -> np.ndarray:
    """Reshape one frame (or (n, dims*V) frames) to points with 3 coordinates (z = 0 for 2-D)."""
    row = np.asarray(row)
    pts = row.reshape(*row.shape[:-1], -1, dims)
    if dims == 2:
        pts = np.concatenate([pts, np.zeros(pts.shape[:-1] + (1,), pts.dtype)], axis=-1)
    return pts
