"""The corpus: frames of lip geometry, utterances and their phone alignments.

A :class:`Corpus` is the input to everything in the engine. Frames never connect
across utterance boundaries: no velocity, transition or path crosses one.
"""
from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from engine.recordings.corpus_format import (
    FORMAT_VERSION,
    corpus_from_arrays,
    corpus_to_arrays,
    load_corpus,
    save_corpus,
)
from engine.recordings.frame_blocks import BlockFrames
from engine.recordings.utterances import (
    CorpusError,
    CorpusWarning,
    PhoneInterval,
    Utterance,
    _as_phones,
    frame_points,
    label_codes,
)

__all__ = ["CorpusError", "CorpusWarning", "PhoneInterval", "Utterance", "Corpus", "label_codes", "frame_points",
           "FORMAT_VERSION"]

#: largest coordinate magnitude a corpus holds (the importers treat larger samples as dropouts)
MAX_COORDINATE = 1e6


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
        # frames stored in blocks stay there (engine.recordings.frame_blocks)
        if not isinstance(self.frames, BlockFrames):
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

    # -------------------------------------------------------------- file i/o (engine.recordings.corpus_format)
    def to_arrays(self, *, include_frames: bool = True,
                  base: str | os.PathLike[str] | None = None) -> dict[str, np.ndarray]:
        """Flat dict of arrays for ``np.savez`` (no pickled objects; :mod:`engine.recordings.corpus_format`).

        ``base``: the folder of the file the arrays go to. Audio paths are then stored
        relative to it (``corpus_utt_audio``), so a folder moved with its sound keeps it, and
        absolute as well (``corpus_utt_audio_abs``), for a corpus file moved on its own.
        """
        return corpus_to_arrays(self, include_frames=include_frames, base=base)

    @classmethod
    def from_arrays(cls, d: Mapping[str, Any], *, frames: Any = None, source: str = "<arrays>",
                    base: str | os.PathLike[str] | None = None) -> Corpus:
        """Inverse of :meth:`to_arrays`; ``frames`` overrides the stored frames.

        ``base``: the folder of the file read. A relative audio path is taken relative to it
        (made absolute); when that file is missing and the absolute path stored beside it
        exists, that one. Absolute paths (files written before) are kept.
        """
        return corpus_from_arrays(cls, d, frames=frames, source=source, base=base)

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the native corpus file (``.npz``) atomically."""
        return save_corpus(self, path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Corpus:
        """Read a native corpus file written by :meth:`save`."""
        return load_corpus(cls, path)
