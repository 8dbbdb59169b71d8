"""A corpus stored in blocks of frames on disk, for builds whose workers read their own blocks (issue 13).

Layout, written by :func:`save_blocked` (``lipspace import --block-frames N``)::

    OUT.npz             the corpus without its frames (utterances, phones, names, ...),
                        plus ``blocks_files`` (block file names) and ``blocks_frames``
                        (frames per block)
    OUT.blocks/         block_00000.npy, block_00001.npy, ... : F in row blocks, float32,
                        each a plain .npy that a worker memory-maps (np.load(mmap_mode="r"))

:func:`load_blocked` reads it back as an ordinary :class:`engine.corpus.Corpus` (the
frames gathered from the blocks) together with the block paths, which
:meth:`engine.scale.DaskExecutor.use_frame_blocks` hands to the workers so that the
shape stage reads the blocks in place instead of writing F out again. For a cluster
the folder must be on storage every worker can read.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from engine._atomic import atomic_write
from engine.corpus import Corpus, CorpusError

__all__ = ["save_blocked", "load_blocked", "is_blocked", "blocks_folder"]


def blocks_folder(path) -> Path:
    """``OUT.blocks`` beside ``OUT.npz``."""
    path = Path(path)
    return path.with_name(path.stem + ".blocks")


def save_blocked(corpus: Corpus, path, *, block_frames: int = 8192) -> list[Path]:
    """Write ``corpus`` as ``path`` (.npz, no frames) and its frames as blocks in ``OUT.blocks/``.

    Parameters
    ----------
    corpus : Corpus
    path : str or Path
        The corpus file (.npz).
    block_frames : int, default=8192
        Frames per block (a last block shorter than half of it joins the one before).

    Returns
    -------
    list of Path
        The block files in frame order.
    """
    from engine.scale import store_frame_blocks

    if isinstance(block_frames, bool) or not isinstance(block_frames, (int, np.integer)) or block_frames < 256:
        raise ValueError(f"block_frames must be an integer >= 256 (each block taller than the shape range finder "
                         f"is wide), got {block_frames!r}")
    path = Path(path)
    folder = blocks_folder(path)
    for old in folder.glob("block_*.npy") if folder.is_dir() else []:
        old.unlink()  # a previous import's blocks would be mixed with these
    paths = store_frame_blocks(corpus.frames, folder, block_frames=int(block_frames))
    d = corpus.to_arrays(include_frames=False)
    d["blocks_files"] = np.array([p.name for p in paths], dtype=str)
    d["blocks_frames"] = np.array([np.load(p, mmap_mode="r").shape[0] for p in paths], dtype=np.int64)
    with atomic_write(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **d)
    return paths


def is_blocked(path) -> bool:
    """Whether ``path`` is a corpus file whose frames are stored in blocks."""
    from engine._persist import NpzReadError, read_npz

    try:
        keys = read_npz(path, keys_only=True)
    except (OSError, NpzReadError):
        return False
    return "blocks_files" in keys and "corpus_frames" not in keys


def load_blocked(path) -> tuple[Corpus, list[Path]]:
    """Read a corpus written by :func:`save_blocked`: ``(corpus, block paths)``.

    Every block is checked against the corpus file (present, 2-D float32, the recorded
    number of frames, the corpus's number of coordinates) before it is used; a fault
    raises :class:`engine.corpus.CorpusError` naming the block file.
    """
    from engine._persist import NpzReadError, read_npz

    path = Path(path)
    try:
        d = read_npz(path)
    except NpzReadError as exc:
        raise CorpusError(f"{path}: not a readable .npz corpus file ({exc.reason})") from None
    if "blocks_files" not in d:
        raise CorpusError(f"{path}: not a corpus stored in blocks (no 'blocks_files'); read it with Corpus.load")
    folder = blocks_folder(path)
    names, counts = [str(n) for n in d["blocks_files"]], np.asarray(d["blocks_frames"])
    n_cols = int(d["corpus_n_columns"])
    if len(names) != len(counts) or not names:
        raise CorpusError(f"{path}: field 'blocks_files' names {len(names)} blocks but 'blocks_frames' has "
                          f"{len(counts)} counts")
    paths, parts = [], []
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
        paths.append(p)
        parts.append(b)
    frames = np.concatenate(parts)
    if frames.shape[0] != int(d["corpus_n_frames"]):
        raise CorpusError(f"{path}: the blocks hold {frames.shape[0]} frames but the corpus has "
                          f"{int(d['corpus_n_frames'])}")
    return Corpus.from_arrays(d, frames=frames, source=str(path)), paths
