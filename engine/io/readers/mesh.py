"""Mesh sequences (one OBJ / PLY file per frame) and NumPy vertex arrays with a template
mesh (VOCASET-style), as 3-D corpora. Neither carries timing: the frame rate is an argument."""
from __future__ import annotations

import glob as _glob
from pathlib import Path

import numpy as np

from engine.io._util import fill_gaps as _fill_gaps
from engine.io._util import natural_key, one_utterance_corpus, plausible_rate, sidecar_audio
from engine.io.errors import ImportFormatError
from engine.io.readers.alignment import resolve_alignment
from engine.io.readers.meshfile import read_mesh
from engine.io.repairs import reports_repairs

__all__ = ["read_mesh_sequence", "read_vertex_array", "mesh_sequence_files"]

MESH_SUFFIXES = (".obj", ".ply")


def _vertex_column(j: int) -> str:
    return f"vertex {j // 3} {'xyz'[j % 3]}"


def _need_rate(where, rate):
    if rate is None:
        raise ImportFormatError(where, "mesh frames carry no timing; give the frame rate (lipspace import "
                                "--rate HZ)")
    return plausible_rate(where, rate, "the frame rate given (--rate)")


def mesh_sequence_files(source) -> tuple[list[Path], Path]:
    """The frame files of a mesh sequence, in natural order, and the path naming the sequence.

    ``source`` is a directory (its ``.obj`` or ``.ply`` files), a glob pattern, or a
    sequence of file paths.
    """
    if isinstance(source, (list, tuple)):
        files = [Path(p) for p in source]
        where = files[0].parent if files else Path(".")
    else:
        s = str(source)
        if any(c in s for c in "*?["):
            files = [Path(p) for p in _glob.glob(s)]
            where = Path(s).parent
        else:
            where = Path(s)
            if not where.exists():
                raise FileNotFoundError(f"{where}: no such file or directory")
            if not where.is_dir():
                raise ImportFormatError(where, "is one mesh file, i.e. one frame; expected a directory of frame "
                                        "files or a glob pattern such as 'frames/*.obj'")
            files = [p for p in where.iterdir() if p.suffix.lower() in MESH_SUFFIXES and p.is_file()]
            kinds = {p.suffix.lower() for p in files}
            if len(kinds) > 1:
                raise ImportFormatError(where, f"holds both {sorted(kinds)} files; expected one kind of frame file "
                                        "(pass a glob such as 'dir/*.obj')")
    files = sorted(files, key=lambda p: natural_key(p.name))
    if len(files) < 2:
        raise ImportFormatError(where, f"{len(files)} mesh frame file(s) found; expected at least 2 .obj/.ply files")
    return files, where


@reports_repairs
def read_mesh_sequence(source, *, rate: float | None = None, alignment=None, tier: str | None = None,
                       fill_gaps: bool = True, name: str | None = None):
    """One utterance from one mesh file per frame.

    Parameters
    ----------
    source : directory, glob pattern or sequence of paths
        Frame files (OBJ or PLY), taken in natural order (``f2`` before ``f10``).
    rate : float
        Frames per second (required: mesh files carry no timing).
    alignment : None, False, path or sequence of PhoneInterval
        Phones; by default ``<dir>.TextGrid`` / ``<dir>.lab`` beside the directory.
    tier : str, optional
    fill_gaps : bool
        Interpolate non-finite vertex coordinates; else raise.
    name : str, optional
        Utterance id (default: the directory's name).

    Returns
    -------
    Corpus
        ``frames`` (n_files, 3V) float32, ``faces`` from the first file (every file must
        have the same vertex count and the same faces).
    """
    files, where = mesh_sequence_files(source)
    rate = _need_rate(where, rate)
    V0, F0 = read_mesh(files[0])
    frames = np.empty((len(files), V0.size), np.float32)
    frames[0] = V0.ravel()
    for k, f in enumerate(files[1:], start=1):
        V, F = read_mesh(f)
        if V.shape != V0.shape:
            raise ImportFormatError(f, f"has {V.shape[0]} vertices; {files[0].name} (frame 0) has {V0.shape[0]}; "
                                    "expected the same vertex count in every frame", frame=k)
        if (F is None) != (F0 is None) or (F is not None and not np.array_equal(F, F0)):
            raise ImportFormatError(f, f"its faces differ from {files[0].name}'s (frame 0); expected one mesh "
                                    "topology for the whole sequence", frame=k)
        frames[k] = V.ravel()
    uid = name or where.name or "mesh"
    frames = _fill_gaps(frames, np.zeros(len(frames), bool), path=where, fill=fill_gaps, names=_vertex_column)
    phones, _ = resolve_alignment(where, alignment, tier=tier)
    return one_utterance_corpus(where, frames, rate, dims=3, uid=uid, phones=phones, faces=F0, units="",
                                audio=sidecar_audio(where))


def _load_npy(path) -> np.ndarray:
    """An .npy array, its header checked against the file size before anything is allocated."""
    fmt = np.lib.format
    try:
        with open(path, "rb") as fh:
            version = fmt.read_magic(fh)
            if version == (1, 0):
                shape, _, dtype = fmt.read_array_header_1_0(fh)
            elif version == (2, 0):
                shape, _, dtype = fmt.read_array_header_2_0(fh)
            else:
                raise ValueError(f"unsupported .npy version {version}")
            if dtype.hasobject:
                raise ValueError("it holds Python objects")
            need = int(np.prod(shape, dtype=np.float64)) * dtype.itemsize
            have = path.stat().st_size - fh.tell()
            if have < need:
                raise ValueError(f"the header promises {shape} {dtype} ({need} bytes) but {have} bytes follow; "
                                 "truncated file?")
            fh.seek(0)
            return np.load(fh, allow_pickle=False)
    except Exception as exc:  # ValueError (not .npy / pickled), OSError, EOFError, ...
        raise ImportFormatError(path, f"is not a readable .npy array ({exc})") from None


@reports_repairs
def read_vertex_array(path, *, template=None, rate: float | None = None, alignment=None, tier: str | None = None,
                      fill_gaps: bool = True):
    """A NumPy vertex array (VOCASET-style) as one utterance.

    Parameters
    ----------
    path : str or Path
        ``.npy`` of shape (n_frames, V, 3) or (n_frames, 3V).
    template : str or Path, optional
        OBJ/PLY mesh with the same V vertices whose faces are used.
    rate : float
        Frames per second (required).
    alignment, tier, fill_gaps : as :func:`read_mesh_sequence`

    Returns
    -------
    Corpus
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    arr = _load_npy(path)
    if not isinstance(arr, np.ndarray) or not np.issubdtype(arr.dtype, np.number) or \
            np.issubdtype(arr.dtype, np.complexfloating):
        raise ImportFormatError(path, f"holds {getattr(arr, 'dtype', type(arr))}; expected a real numeric array")
    if arr.ndim == 3 and arr.shape[2] == 3:
        n, V = arr.shape[0], arr.shape[1]
    elif arr.ndim == 2 and arr.shape[1] % 3 == 0:
        n, V = arr.shape[0], arr.shape[1] // 3
    else:
        raise ImportFormatError(path, f"has shape {arr.shape}; expected (n_frames, V, 3) or (n_frames, 3V)")
    if V == 0:
        raise ImportFormatError(path, f"has shape {arr.shape}: no vertices")
    rate = _need_rate(path, rate)
    faces = None
    if template is not None:
        TV, faces = read_mesh(template)
        if TV.shape[0] != V:
            raise ImportFormatError(template, f"the template has {TV.shape[0]} vertices; {path.name} has {V}; "
                                    "expected the same mesh")
    with np.errstate(over="ignore", invalid="ignore"):  # out-of-range values become inf: gaps
        frames = np.asarray(arr, dtype=np.float32).reshape(n, 3 * V)
    frames = _fill_gaps(frames, np.zeros(len(frames), bool), path=path, fill=fill_gaps, names=_vertex_column)
    phones, _ = resolve_alignment(path, alignment, tier=tier)
    return one_utterance_corpus(path, frames, rate, dims=3, phones=phones, faces=faces, audio=sidecar_audio(path),
                                units="")  # meshes carry no unit (VOCASET: metres)
