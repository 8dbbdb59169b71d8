"""Frames read a window at a time from block files, never gathered whole.

:class:`BlockFrames` stands for the frame matrix F (N, C) float32 of a corpus stored in
blocks (``engine.recordings.corpus_blocks``): it holds only the block file paths, the rows each
block holds and, after per-speaker normalisation, the small per-speaker affine map
(:class:`SpeakerAffine`). Rows are read on demand (``F[a:b]``, ``F[i]``, ``F[index
array]``); each read memory-maps the block files it touches, copies the rows out and
drops the mapping, so the reading process never keeps N x C in memory. The object is
small and picklable: a Dask worker given it reads its own block (:meth:`BlockFrames.rows`).

:func:`map_frames` runs a per-row function over F window by window: in-process over
fixed windows of global rows (:func:`row_windows`: the same windows for an in-memory
array and for block files, so in-process results do not depend on how F is stored),
or, given an executor with ``map_frame_blocks`` (``engine.scale.executor.DaskExecutor``), as one
task per block file.

``np.asarray(F)`` (and :meth:`BlockFrames.astype`) gathers every row: it is there for the
callers that need a whole matrix (a figure, a small corpus) and is never used by a build.
"""
from __future__ import annotations

import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from engine.files.atomic import atomic_write

__all__ = ["BlockFrames", "SpeakerAffine", "map_frames", "row_windows", "speaker_runs", "WINDOW_ROWS", "WINDOW_BYTES",
           "store_frame_blocks", "block_slices", "DEFAULT_BLOCK_FRAMES"]

#: rows per window of the in-process loops over F (:func:`row_windows`), at most
WINDOW_ROWS = 8192
#: bytes of float32 rows per window at most (wide frames: fewer rows)
WINDOW_BYTES = 32 * 2**20
#: rows converted to float64 at once when the speaker normalisation is applied
_AFFINE_ROWS = 1024


def row_windows(n: int, n_columns: int):
    """``(start, stop)`` of consecutive windows covering ``range(n)``: :data:`WINDOW_ROWS` rows, fewer
    when rows of ``n_columns`` float32 values would exceed :data:`WINDOW_BYTES` (at least 64)."""
    rows = max(64, min(WINDOW_ROWS, WINDOW_BYTES // (4 * max(1, int(n_columns)))))
    for a in range(0, int(n), int(rows)):
        yield a, min(int(n), a + int(rows))


def speaker_runs(utt_starts, utt_code, a: int, b: int):
    """``(speaker, start, stop)``: runs of the global rows ``[a, b)`` spoken by one speaker, given every
    utterance's first frame ``utt_starts`` (U,) and speaker number ``utt_code`` (U,)."""
    if b <= a:
        return
    first = int(np.searchsorted(utt_starts, a, side="right")) - 1
    last = int(np.searchsorted(utt_starts, b - 1, side="right")) - 1
    start = a
    for u in range(first, last + 1):
        stop = b if u == last else int(utt_starts[u + 1])
        s = int(utt_code[u])
        if u < last and int(utt_code[u + 1]) == s:
            continue  # the next utterance has the same speaker: one run
        yield s, start, stop
        start = stop


@dataclass(frozen=True)
class SpeakerAffine:
    """Per-speaker normalisation of frames: row r of speaker s becomes
    ``((F[r] - mean[s]) * factor[s] + grand)`` (float64 arithmetic, float32 result).

    Parameters
    ----------
    utt_starts : int ndarray of shape (U,)
        First frame of every utterance (increasing, the first 0).
    utt_code : int ndarray of shape (U,)
        Speaker number of every utterance (0..S-1).
    mean : float64 ndarray of shape (S, C)
        Each speaker's mean frame.
    factor : float64 ndarray of shape (S,) or None
        Each speaker's spread scaling (None: not scaled, the "mean" mode).
    grand : float64 ndarray of shape (C,)
        The pooled mean frame, added back.
    """

    utt_starts: np.ndarray
    utt_code: np.ndarray
    mean: np.ndarray
    factor: np.ndarray | None
    grand: np.ndarray

    def then(self, other: SpeakerAffine) -> SpeakerAffine:
        """One map doing ``self`` and then ``other`` (normalising frames normalised already)."""
        f1 = np.ones(len(self.mean)) if self.factor is None else self.factor
        mean = self.mean + (other.mean - self.grand) / f1[:, None]
        factor = None if self.factor is None and other.factor is None else f1 * (
            1.0 if other.factor is None else other.factor)
        return SpeakerAffine(self.utt_starts, self.utt_code, mean, factor, other.grand)

    def apply(self, x, a: int) -> np.ndarray:
        """Normalised rows ``[a, a + len(x))`` of F from their raw values ``x`` (n, C): a new float32 array."""
        out = np.empty(x.shape, dtype=np.float32)
        for s, r0, r1 in speaker_runs(self.utt_starts, self.utt_code, a, a + x.shape[0]):
            for c0 in range(r0, r1, _AFFINE_ROWS):  # float64 temporaries of a bounded size
                c1 = min(r1, c0 + _AFFINE_ROWS)
                out[c0 - a:c1 - a] = self._speaker_rows(x[c0 - a:c1 - a], s)
        return out

    def apply_at(self, x, index) -> np.ndarray:
        """Normalised rows ``index`` (n,) of F from their raw values ``x`` (n, C), any order."""
        index = np.asarray(index, dtype=np.int64)
        code = self.utt_code[np.searchsorted(self.utt_starts, index, side="right") - 1]
        out = np.empty(x.shape, dtype=np.float32)
        for s in np.unique(code):
            sel = np.flatnonzero(code == s)
            for c0 in range(0, sel.size, _AFFINE_ROWS):
                rows = sel[c0:c0 + _AFFINE_ROWS]
                out[rows] = self._speaker_rows(x[rows], s)
        return out

    def _speaker_rows(self, x, s) -> np.ndarray:
        """Raw rows ``x`` (n, C) of speaker ``s`` normalised, float64 (n, C)."""
        y = x.astype(np.float64)
        y -= self.mean[s]
        if self.factor is not None:
            y *= self.factor[s]
        y += self.grand
        return y


class BlockFrames:
    """F (N, C) float32 stored as 2-D float32 ``.npy`` block files, read a window at a time.

    Parameters
    ----------
    paths : sequence of path
        The block files in frame order.
    counts : sequence of int
        Rows of every block.
    n_columns : int
        C, the coordinates per frame.
    source : str or None
        The corpus file these blocks belong to (``engine.recordings.corpus_blocks``), if any.
    normalisation : SpeakerAffine or None
        Applied to every row read.

    Attributes
    ----------
    shape : (int, int)
    dtype : numpy.dtype (float32)
    starts : int ndarray of shape (B + 1,)
        First row of every block, then N.
    """

    ndim = 2
    dtype = np.dtype(np.float32)

    def __init__(self, paths, counts, n_columns: int, *, source=None, normalisation: SpeakerAffine | None = None):
        self.paths = tuple(str(p) for p in paths)
        counts = np.asarray(counts, dtype=np.int64).reshape(-1)
        if len(counts) != len(self.paths) or not len(counts) or (counts <= 0).any():
            raise ValueError(f"{len(self.paths)} block files with {len(counts)} row counts "
                             f"({counts.tolist()[:5]}); expected one positive count per file")
        self.starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        self.shape = (int(self.starts[-1]), int(n_columns))
        self.source = None if source is None else str(source)
        self.normalisation = normalisation
        self._token = uuid.uuid4().hex

    @classmethod
    def from_files(cls, paths, *, source=None) -> BlockFrames:
        """Blocks named by ``paths``, their row counts read from the .npy headers (each checked:
        2-D float32, all of one width)."""
        counts, widths = [], set()
        for p in paths:
            hdr = np.load(p, mmap_mode="r")
            if hdr.ndim != 2 or hdr.dtype != np.float32:
                raise ValueError(f"{p}: expected a 2-D float32 block of frames, got {hdr.dtype} {hdr.shape}")
            counts.append(hdr.shape[0])
            widths.add(hdr.shape[1])
            del hdr
        if not counts:
            raise ValueError("no block files given")
        if len(widths) != 1:
            raise ValueError(f"block files disagree on the number of coordinates: {sorted(widths)}")
        return cls(paths, counts, widths.pop(), source=source)

    def with_normalisation(self, normalisation: SpeakerAffine | None) -> BlockFrames:
        """The same blocks read through ``normalisation`` after the normalisation this object already
        carries, if any (a new object; the files are not touched)."""
        if self.normalisation is not None and normalisation is not None:
            normalisation = self.normalisation.then(normalisation)
        return BlockFrames(self.paths, np.diff(self.starts), self.shape[1], source=self.source,
                           normalisation=normalisation)

    # -------------------------------------------------------------- array-like
    @property
    def size(self) -> int:
        return self.shape[0] * self.shape[1]

    @property
    def nbytes(self) -> int:
        """Bytes of F as a whole float32 matrix (what gathering it would take)."""
        return self.size * 4

    def __len__(self) -> int:
        return self.shape[0]

    def __repr__(self) -> str:
        norm = ", speaker-normalised" if self.normalisation is not None else ""
        return f"BlockFrames({self.shape[0]} x {self.shape[1]} in {len(self.paths)} block files{norm})"

    def __dask_tokenize__(self):
        return ("BlockFrames", self._token)

    @property
    def block_bounds(self) -> list[tuple[int, int]]:
        """``(start, stop)`` rows of every block file."""
        return [(int(a), int(b)) for a, b in zip(self.starts[:-1], self.starts[1:])]

    def _raw(self, a: int, b: int) -> np.ndarray:
        """Rows ``[a, b)`` as stored, copied out of the memory-mapped block files."""
        out = np.empty((max(0, b - a), self.shape[1]), dtype=np.float32)
        if b <= a:
            return out
        first = int(np.searchsorted(self.starts, a, side="right")) - 1
        last = int(np.searchsorted(self.starts, b - 1, side="right")) - 1
        for k in range(first, last + 1):
            s0, s1 = int(self.starts[k]), int(self.starts[k + 1])
            lo, hi = max(a, s0), min(b, s1)
            mm = self._open(k)
            out[lo - a:hi - a] = mm[lo - s0:hi - s0]
            del mm  # the mapping goes with the last reference: its pages leave this process
        return out

    def _open(self, k: int):
        p = self.paths[k]
        try:
            mm = np.load(p, mmap_mode="r", allow_pickle=False)
        except FileNotFoundError:
            raise FileNotFoundError(f"{p}: block file missing (block {k} of the frames of "
                                    f"{self.source or 'this corpus'})") from None
        want = (int(self.starts[k + 1] - self.starts[k]), self.shape[1])
        if mm.shape != want or mm.dtype != np.float32:
            raise ValueError(f"{p}: expected a float32 block of shape {want}, got {mm.dtype} {mm.shape} "
                             "(the block files changed after the corpus was written)")
        return mm

    def rows(self, a: int, b: int) -> np.ndarray:
        """Rows ``[a, b)`` of F (normalised when this object carries a normalisation): a new
        float32 array of shape (b - a, C)."""
        a, b = int(a), int(b)
        if not 0 <= a <= b <= self.shape[0]:
            raise IndexError(f"rows {a}..{b} outside the {self.shape[0]} frames")
        x = self._raw(a, b)
        return x if self.normalisation is None else self.normalisation.apply(x, a)

    def take(self, index) -> np.ndarray:
        """Rows ``index`` (int array, any order, repeats allowed) of F, shape (len(index), C)."""
        idx = np.asarray(index)
        if idx.dtype == bool:
            if idx.shape != (self.shape[0],):
                raise IndexError(f"boolean index of shape {idx.shape} for {self.shape[0]} frames")
            idx = np.flatnonzero(idx)
        idx = idx.astype(np.int64).reshape(-1)
        if idx.size and (idx.min() < -self.shape[0] or idx.max() >= self.shape[0]):
            raise IndexError(f"frame index out of range for {self.shape[0]} frames")
        idx = np.where(idx < 0, idx + self.shape[0], idx)
        out = np.empty((idx.size, self.shape[1]), dtype=np.float32)
        order = np.argsort(idx, kind="stable")
        sorted_idx = idx[order]
        block_of = np.searchsorted(self.starts, sorted_idx, side="right") - 1
        for k in np.unique(block_of):
            sel = order[block_of == k]
            mm = self._open(int(k))
            out[sel] = mm[idx[sel] - int(self.starts[k])]
            del mm
        return out if self.normalisation is None else self.normalisation.apply_at(out, idx)

    def __getitem__(self, key):
        if isinstance(key, tuple):
            if len(key) != 2:
                raise IndexError(f"F is 2-D; got an index of {len(key)} parts")
            rows = self[key[0]]
            return rows[..., key[1]]
        if isinstance(key, (int, np.integer)):
            i = int(key) + (self.shape[0] if key < 0 else 0)
            if not 0 <= i < self.shape[0]:
                raise IndexError(f"frame {int(key)} out of range for {self.shape[0]} frames")
            return self.rows(i, i + 1)[0]
        if isinstance(key, slice):
            a, b, step = key.indices(self.shape[0])
            if step == 1:
                return self.rows(a, max(a, b))
            return self.take(np.arange(a, b, step))
        return self.take(key)

    def __array__(self, dtype=None, copy=None):
        out = np.empty(self.shape, dtype=np.float32)
        for a, b in self.block_bounds:
            out[a:b] = self.rows(a, b)
        return out if dtype is None else out.astype(dtype, copy=False)

    def astype(self, dtype, copy=True):
        """Every row gathered as one array of ``dtype`` (N x C in memory)."""
        return np.asarray(self).astype(dtype, copy=False)

    def mean(self, axis=None, dtype=None):
        """Mean frame (``axis=0``), summed window by window in float64."""
        if axis != 0:
            raise ValueError("BlockFrames.mean computes only the mean frame (axis=0)")
        total = np.zeros(self.shape[1], dtype=np.float64)
        for a, b in row_windows(*self.shape):
            total += self.rows(a, b).sum(axis=0, dtype=np.float64)
        return (total / self.shape[0]).astype(dtype or np.float32)


def map_frames(fn, frames, *, executor=None) -> list:
    """``[fn(F[a:b], a, b), ...]`` over F in row order.

    ``frames`` is an ndarray or a :class:`BlockFrames`. Without an executor (or one
    without ``map_frame_blocks``, or for an in-memory F) the loop runs here over the
    windows of :func:`row_windows`; with ``engine.scale.executor.DaskExecutor`` and block files, one
    task per block file runs on the worker that reads it. ``fn`` must be picklable for
    Dask (a module-level function or a ``functools.partial`` of one).
    """
    if executor is not None and isinstance(frames, BlockFrames) and hasattr(executor, "map_frame_blocks"):
        return executor.map_frame_blocks(fn, frames)
    return [fn(frames[a:b], a, b) for a, b in row_windows(*frames.shape)]


#: frames per on-disk block of F (and per task of the shape stage)
DEFAULT_BLOCK_FRAMES = 8192


def block_slices(n: int, block: int) -> list[slice]:
    """Row blocks of ``block`` rows; a last block shorter than half a block joins the one before
    (every block stays taller than it is wide, as the tall-skinny QR needs)."""
    starts = list(range(0, n, block))
    if len(starts) > 1 and n - starts[-1] < block // 2:
        starts.pop()
    return [slice(s, starts[i + 1] if i + 1 < len(starts) else n) for i, s in enumerate(starts)]


def store_frame_blocks(frames, directory, *, block_frames: int = DEFAULT_BLOCK_FRAMES) -> list[Path]:
    """Write F (N, C) as ``block_00000.npy``, ... (float32, one per block of frames), atomically.

    Returns
    -------
    list of Path
        The block files in frame order.
    """
    frames = np.asarray(frames)
    if frames.ndim != 2:
        raise ValueError(f"frames must be 2-D (N, C), got shape {frames.shape}")
    if int(block_frames) < 2:
        raise ValueError(f"block_frames must be >= 2, got {block_frames}")
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for i, sl in enumerate(block_slices(frames.shape[0], int(block_frames))):
        path = directory / f"block_{i:05d}.npy"
        with atomic_write(path) as tmp:
            with open(tmp, "wb") as fh:
                np.save(fh, np.ascontiguousarray(frames[sl], dtype=np.float32))
        paths.append(path)
    return paths
