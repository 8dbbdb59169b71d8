"""A corpus stored in blocks of frames on disk, for builds whose workers read their own blocks.

Layout, written by :func:`save_blocked` (``lipspace import --block-frames N``)::

    OUT.npz             the corpus without its frames (utterances, phones, names, ...),
                        plus ``blocks_files`` (block file names) and ``blocks_frames``
                        (frames per block)
    OUT.blocks/         block_00000.npy, block_00001.npy, ... : F in row blocks, float32,
                        each a plain .npy that a worker memory-maps (np.load(mmap_mode="r"))

:func:`load_blocked` reads it back as an :class:`engine.recordings.corpus.Corpus` whose frames are
an :class:`engine.recordings.frame_blocks.BlockFrames`: the block paths and row counts, never the
frames gathered into memory. Every stage of a build reads them a window (in-process) or
a block file (Dask workers) at a time. For a cluster the folder must be on storage every
worker can read.

A manifold built from such a corpus does not copy its frames: its file references the
corpus file (:func:`frames_reference`: the path as given, and relative to the manifold's
folder) with the per-speaker normalisation as small matrices, and
:func:`frames_from_reference` reopens the blocks when the manifold is loaded; a missing
corpus file is an error naming it.
"""
from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from engine.files.atomic import atomic_write
from engine.recordings.corpus import Corpus, CorpusError
from engine.recordings.frame_blocks import BlockFrames, SpeakerAffine

__all__ = ["save_blocked", "load_blocked", "is_blocked", "blocks_folder", "frames_reference", "frames_from_reference"]


def blocks_folder(path: str | os.PathLike[str]) -> Path:
    """``OUT.blocks`` beside ``OUT.npz``."""
    path = Path(path)
    return path.with_name(path.stem + ".blocks")


def save_blocked(corpus: Corpus, path: str | os.PathLike[str], *, block_frames: int = 8192,
                 folder: str | os.PathLike[str] | None = None) -> list[Path]:
    """Write ``corpus`` as ``path`` (.npz, no frames) and its frames as blocks in ``OUT.blocks/``.

    Parameters
    ----------
    corpus : Corpus
    path : str or Path
        The corpus file (.npz).
    block_frames : int, default=8192
        Frames per block (a last block shorter than half of it joins the one before).
    folder : str or Path, optional
        Where to write the blocks instead of :func:`blocks_folder` of ``path`` (a staging
        folder whose files are moved there afterwards: :class:`engine.files.staging.Outputs`).

    Returns
    -------
    list of Path
        The block files in frame order.
    """
    from engine.recordings.frame_blocks import store_frame_blocks

    if isinstance(block_frames, bool) or not isinstance(block_frames, (int, np.integer)) or block_frames < 256:
        raise ValueError(f"block_frames must be an integer >= 256 (each block taller than the shape range finder "
                         f"is wide), got {block_frames!r}")
    path = Path(path)
    folder = blocks_folder(path) if folder is None else Path(folder)
    for old in folder.glob("block_*.npy") if folder.is_dir() else []:
        old.unlink()  # a previous import's blocks would be mixed with these
    paths = store_frame_blocks(corpus.frames, folder, block_frames=int(block_frames))
    d = corpus.to_arrays(include_frames=False, base=path.resolve().parent)
    d["blocks_files"] = np.array([p.name for p in paths], dtype=str)
    d["blocks_frames"] = np.array([np.load(p, mmap_mode="r").shape[0] for p in paths], dtype=np.int64)
    with atomic_write(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **d)  # type: ignore[arg-type]  # numpy types only the positional arrays
    return paths


def is_blocked(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is a corpus file whose frames are stored in blocks."""
    from engine.files.persist import NpzReadError, read_npz

    try:
        keys = read_npz(path, keys_only=True)
    except (OSError, NpzReadError):
        return False
    return "blocks_files" in keys and "corpus_frames" not in keys


def load_blocked(path: str | os.PathLike[str]) -> Corpus:
    """Read a corpus written by :func:`save_blocked`.

    The corpus's frames are an :class:`engine.recordings.frame_blocks.BlockFrames` over the block
    files (nothing is gathered; ``corpus.frames.paths`` names them in frame order).
    Every block's header is checked against the corpus file (present, 2-D float32, the
    recorded number of frames, the corpus's number of coordinates) before it is used; a
    fault raises :class:`engine.recordings.corpus.CorpusError` naming the block file. NaN/inf in the
    blocks are found where they are read (the shape stage names the frame).
    """
    from engine.files.persist import NpzReadError, read_npz

    path = Path(path)
    try:
        d = read_npz(path, memory_map=None)  # per-frame metadata (e.g. a talker's latents) stays on disk
    except NpzReadError as exc:
        raise CorpusError(f"{path}: not a readable .npz corpus file ({exc.reason})") from None
    return Corpus.from_arrays(d, frames=_open_blocks(path, d), source=str(path), base=path.resolve().parent)


def _open_blocks(path: Path, d: Mapping[str, Any]) -> BlockFrames:
    """The :class:`BlockFrames` of the blocked corpus file ``path`` whose arrays are ``d``."""
    if "blocks_files" not in d:
        raise CorpusError(f"{path}: not a corpus stored in blocks (no 'blocks_files'); read it with Corpus.load")
    folder = blocks_folder(path)
    names, counts = [str(n) for n in d["blocks_files"]], np.asarray(d["blocks_frames"]).reshape(-1)
    n_cols = int(d["corpus_n_columns"])
    if len(names) != len(counts) or not names:
        raise CorpusError(f"{path}: field 'blocks_files' names {len(names)} blocks but 'blocks_frames' has "
                          f"{len(counts)} counts")
    paths = []
    for name, n in zip(names, counts):
        p = folder / name
        if Path(name).name != name or not p.is_file():
            raise CorpusError(f"{p}: block file missing (expected beside the corpus in {folder.name}/)")
        try:
            b = np.load(p, mmap_mode="r", allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise CorpusError(f"{p}: not a readable .npy block ({exc})") from None
        if b.dtype != np.float32 or b.ndim != 2 or b.shape != (int(n), n_cols):
            raise CorpusError(f"{p}: expected a float32 block of shape ({int(n)}, {n_cols}), got {b.dtype} "
                              f"{b.shape}")
        del b
        paths.append(p)
    if int(counts.sum()) != int(d["corpus_n_frames"]):
        raise CorpusError(f"{path}: the blocks hold {int(counts.sum())} frames but the corpus has "
                          f"{int(d['corpus_n_frames'])}")
    return BlockFrames(paths, counts, n_cols, source=path.resolve())


# ------------------------------------------------------------ manifold files
#: fields of a manifold file that reference a blocked corpus instead of holding its frames
REFERENCE_FIELDS = ("corpus_blocks_source", "corpus_blocks_relative")
_NORM = ("corpus_blocks_norm_mean", "corpus_blocks_norm_grand", "corpus_blocks_norm_code")


def frames_reference(frames: BlockFrames, manifold_path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Fields for a manifold file at ``manifold_path`` standing for ``frames`` (read from a blocked
    corpus file): the corpus file's absolute path and its path relative to the manifold's folder
    (tried first, so the two can move together), and the per-speaker normalisation, if any."""
    if frames.source is None:
        raise ValueError("these frames were not read from a blocked corpus file; save the manifold with "
                         "include_frames=True")
    src = Path(frames.source)
    try:
        rel = os.path.relpath(src, Path(manifold_path).resolve().parent)
    except ValueError:  # another drive (Windows): the absolute path only
        rel = ""
    d = {"corpus_blocks_source": np.array(str(src)), "corpus_blocks_relative": np.array(rel)}
    norm = frames.normalisation
    if norm is not None:
        d["corpus_blocks_norm_mean"] = np.asarray(norm.mean, np.float64)
        d["corpus_blocks_norm_grand"] = np.asarray(norm.grand, np.float64)
        d["corpus_blocks_norm_code"] = np.asarray(norm.utt_code, np.int64)
        if norm.factor is not None:
            d["corpus_blocks_norm_factor"] = np.asarray(norm.factor, np.float64)
    return d


def frames_from_reference(d: Mapping[str, Any], manifold_path: str | os.PathLike[str], *, n_frames: int,
                          n_columns: int) -> BlockFrames:
    """Reopen the frames a manifold file references (see :func:`frames_reference`).

    Raises
    ------
    engine.recordings.corpus.CorpusError
        Naming the corpus file when it is missing or no longer holds ``n_frames`` x
        ``n_columns`` frames, or naming the field when the normalisation fields do not fit.
    """
    from engine.files.persist import NpzReadError, read_npz

    manifold_path = Path(manifold_path)
    src = Path(str(d["corpus_blocks_source"]))
    rel = str(d["corpus_blocks_relative"]) if "corpus_blocks_relative" in d else ""
    candidates = ([manifold_path.resolve().parent / rel] if rel else []) + [src]
    found = next((c for c in candidates if c.is_file()), None)
    if found is None:
        raise CorpusError(f"{manifold_path}: the frames of this manifold are in the blocked corpus {src} (with "
                          f"{blocks_folder(src).name}/ beside it), which is missing; put the corpus back there "
                          "(or beside the manifold as when it was built) or rebuild the manifold")
    try:
        cd = read_npz(found, memory_map=None)
    except NpzReadError as exc:
        raise CorpusError(f"{found}: not a readable .npz corpus file ({exc.reason}); this manifold's frames "
                          "are stored there") from None
    frames = _open_blocks(found, cd)
    if frames.shape != (int(n_frames), int(n_columns)):
        raise CorpusError(f"{found}: holds {frames.shape[0]} x {frames.shape[1]} frames but the manifold "
                          f"{manifold_path.name} was built on {n_frames} x {n_columns}: not the corpus it was "
                          "built from; rebuild the manifold")
    if "corpus_blocks_norm_mean" not in d:
        return frames
    mean, grand = np.asarray(d["corpus_blocks_norm_mean"]), np.asarray(d["corpus_blocks_norm_grand"])
    code = np.asarray(d["corpus_blocks_norm_code"])
    factor = np.asarray(d["corpus_blocks_norm_factor"]) if "corpus_blocks_norm_factor" in d else None
    bounds = np.asarray(d["corpus_utt_bounds"])
    S = mean.shape[0] if mean.ndim == 2 else -1
    checks = [("corpus_blocks_norm_mean", mean.ndim == 2 and mean.shape[1] == n_columns and mean.dtype.kind == "f",
               f"float ({S}, {n_columns})"),
              ("corpus_blocks_norm_grand", grand.shape == (n_columns,) and grand.dtype.kind == "f",
               f"float ({n_columns},)"),
              ("corpus_blocks_norm_code", code.shape == (len(bounds),) and code.dtype.kind == "i"
               and (not code.size or (code.min() >= 0 and code.max() < S)), f"int ({len(bounds)},) in 0..{S - 1}"),
              ("corpus_blocks_norm_factor", factor is None or (factor.shape == (S,) and factor.dtype.kind == "f"),
               f"float ({S},)")]
    for field, ok, want in checks:
        if not ok:
            raise CorpusError(f"{manifold_path}: field {field!r} is not {want}")
    finite = all(np.isfinite(a).all() for a in (mean, grand) + (() if factor is None else (factor,)))
    if not finite:
        raise CorpusError(f"{manifold_path}: the speaker normalisation fields hold NaN or inf")
    return frames.with_normalisation(SpeakerAffine(bounds[:, 0].astype(np.int64), code.astype(np.int64), mean,
                                                   factor, grand))
