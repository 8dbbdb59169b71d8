"""One entry point for every corpus format: :func:`read_corpus` picks the reader."""
from __future__ import annotations

import inspect
from dataclasses import replace
from pathlib import Path

from engine.io.errors import ImportFormatError
from engine.io.repairs import reports_repairs

__all__ = ["read_corpus", "detect_format", "FORMATS", "FORMAT_ALIASES"]

#: format name -> (module, reader function, one-line description)
FORMATS = {
    "ema": ("engine.io.readers.ema", "read_ema", "MOCHA-TIMIT EMA: EST Track (binary/ASCII) or ASCII table, 2-D"),
    "mview": ("engine.io.readers.mview", "read_mview", "Haskins / MVIEW .mat EMA structs, 3-D"),
    "c3d": ("engine.io.readers.markers", "read_c3d", "C3D motion-capture markers, 3-D"),
    "mesh": ("engine.io.readers.mesh", "read_mesh_sequence", "OBJ/PLY mesh sequence, one file per frame (needs rate)"),
    "csv": ("engine.io.readers.landmarks", "read_csv_landmarks", "CSV landmark tracks (OpenFace, named or long)"),
    "npy": ("engine.io.readers.mesh", "read_vertex_array", "NumPy vertex array (n, V, 3) + template mesh (needs rate)"),
    "npz": ("engine.recordings.corpus", "Corpus.load", "Lipspace native corpus file"),
    "matrix": ("engine.io.readers.matrix", "read_matrix", "plain numeric matrix (.mat variable, .npy, CSV/TSV without "
               "names, AG500/AG501 .pos, NDI Wave TSV) read through a sensor layout (layout=)"),
    "pos": ("engine.io.readers.articulograph", "read_pos", "Carstens AG500 / AG501 .pos binary"),
    "wave": ("engine.io.readers.articulograph", "read_wave", "NDI Wave TSV export"),
    "video": ("engine.io.video.clips", "read_video",
              "video of a talking face (.mp4 .mov .avi .mkv ...; a folder of them): "
              "FaceMesh lip landmarks, head pose removed, mm (needs the [video] extra)"),
}
FORMAT_ALIASES = {"mocha": "ema", "est": "ema", "haskins": "mview", "mat": "mview", "obj": "mesh", "ply": "mesh",
                  "openface": "csv", "tsv": "csv", "vocaset": "npy", "native": "npz"}
_EXT = {".ema": "ema", ".mat": "mview", ".c3d": "c3d", ".obj": "mesh", ".ply": "mesh", ".csv": "csv",
        ".tsv": "csv", ".txt": "csv", ".npy": "npy", ".npz": "npz", ".pos": "pos",
        **{e: "video" for e in (".mp4", ".m4v", ".mov", ".avi", ".mkv", ".webm", ".mpg", ".mpeg", ".wmv", ".flv")}}
_ALIGN_EXT = (".textgrid", ".lab", ".phn")


def detect_format(path) -> str:
    """The format name for ``path``: by extension, else by the file's first bytes."""
    if isinstance(path, (list, tuple)):
        if not path:
            raise ValueError("no input files given")
        return detect_format(path[0])
    s = str(path)
    p = Path(s)
    if any(c in s for c in "*?["):
        return "mesh"
    if p.is_dir():
        return "video" if _videos_in(p) else "mesh"
    suf = p.suffix.lower()
    if suf in _ALIGN_EXT:
        raise ImportFormatError(p, "is a phone alignment, not lip data; give it with the data file "
                                "(lipspace import DATA --alignment FILE)")
    if suf in _EXT:
        return _EXT[suf]
    if not p.exists():
        raise FileNotFoundError(f"{p}: no such file or directory")
    with open(p, "rb") as fh:
        head = fh.read(512)
    if head.lstrip()[:8] == b"EST_File":
        return "ema"
    if head.startswith(b"MATLAB 5.0"):
        return "mview"
    if head.startswith(b"ply"):
        return "mesh"
    if head.startswith(b"\x93NUMPY"):
        return "npy"
    if head.startswith(b"AG50xDATA"):
        return "pos"
    if head.startswith(b"PK\x03\x04"):
        return "npz"
    if head[4:8] == b"ftyp" or head.startswith(b"\x1a\x45\xdf\xa3") or (head[:4] == b"RIFF" and head[8:12] == b"AVI "):
        return "video"
    if len(head) >= 2 and head[1] == 0x50:
        return "c3d"
    raise ImportFormatError(p, f"cannot tell the format from the name or the first bytes {head[:16]!r}; give "
                            f"it (lipspace import --format one of {', '.join(sorted(FORMATS))})")


def _videos_in(folder) -> list:
    """The video files directly in ``folder``, in natural order (one utterance each)."""
    from engine.io._util import natural_key

    return sorted((f for f in Path(folder).iterdir() if f.is_file() and _EXT.get(f.suffix.lower()) == "video"),
                  key=lambda f: natural_key(f.name))


def _reader(fmt):
    import importlib

    if fmt == "npz":
        return _read_native
    mod, fn, _ = FORMATS[fmt]
    return getattr(importlib.import_module(mod), fn)


@reports_repairs
def _read_native(path, rate=None, alignment=None, tier=None):
    from engine.files.persist import NpzReadError, read_npz
    from engine.io._util import check_rate, fit_phones
    from engine.io.readers.alignment import resolve_alignment
    from engine.recordings.corpus import Corpus

    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such corpus file")
    try:
        arrays = read_npz(path)
    except NpzReadError as exc:
        raise ImportFormatError(path, f"cannot read as a Lipspace corpus (.npz): {exc.reason}") from None
    c = Corpus.from_arrays(arrays, source=str(path), base=path.resolve().parent)
    check_rate(path, c.rate, rate)
    if alignment is None or alignment is False:
        return c
    if len(c.utterances) != 1:
        raise ImportFormatError(path, f"holds {len(c.utterances)} utterances; an alignment can only be given for "
                                "a corpus of one utterance")
    phones, _ = resolve_alignment(path, alignment, tier=tier)
    u = c.utterances[0]
    return replace(c, utterances=[replace(u, phones=fit_phones(phones, u.n_frames, c.rate, path=path))])


def read_corpus(path, *, format: str | None = None, rate: float | None = None, alignment=None, **kw):
    """Read any supported foreign format (or several files) into a :class:`Corpus`.

    Parameters
    ----------
    path : str, Path, or sequence of them
        A file, a directory or glob of mesh frames, or several files (read with the same
        options and joined by :func:`engine.io.concat`, one utterance each).
    format : str, optional
        One of :data:`FORMATS` (or an alias in :data:`FORMAT_ALIASES`); by default from the
        extension, else from the first bytes.
    rate : float, optional
        Frame rate (Hz) of inputs that carry no timing (mesh sequences, ``.npy``, CSV
        without a time column). For formats with their own rate it must agree; to change
        the rate use :func:`engine.io.resample`.
    alignment : None, False, path or sequence of PhoneInterval
        None: the file's own phones or a ``<stem>.TextGrid`` / ``.lab`` beside it; False:
        none; a path: that TextGrid / label file.
    **kw
        Reader options (``sensors``, ``markers``, ``points``, ``template``, ``tier``,
        ``fill_gaps``, ``space``, ``scale`` ...; see each reader).

    Returns
    -------
    Corpus

    Raises
    ------
    ImportFormatError
        Bad file content, naming the file and the line or frame.
    FileNotFoundError
        A missing input.
    """
    if isinstance(path, (list, tuple)) and not path:
        raise ValueError("read_corpus: no input files given")
    if kw.get("layout") is not None and format is None:
        format = "matrix"
    fmt = (format or detect_format(path)).lower()
    fmt = FORMAT_ALIASES.get(fmt, fmt)
    if fmt not in FORMATS:
        raise ValueError(f"format={format!r} is not known; expected one of {sorted(FORMATS)} "
                         f"(or {sorted(FORMAT_ALIASES)})")
    if fmt == "video" and not isinstance(path, (list, tuple)) and Path(str(path)).is_dir():
        videos = _videos_in(path)  # a folder of one speaker's videos, one utterance each (TextGrid / .lab beside)
        if not videos:
            raise ImportFormatError(path, "holds no video files; expected .mp4, .mov, .avi, .mkv ... files")
        from engine.io.video.clips import read_videos

        return read_videos(videos, rate=rate, alignment=alignment, **kw)
    kw.pop("skip_bad", None)  # a folder's option (of its videos); a file is read or refused whole
    if isinstance(path, (list, tuple)) and fmt != "mesh":  # several files: one utterance each
        from engine.io.combine import concat

        paths = list(path)
        if isinstance(alignment, (list, tuple)) and len(alignment) == len(paths) and \
                all(isinstance(a, (str, Path)) for a in alignment):
            aligns = list(alignment)
        elif len(paths) > 1 and isinstance(alignment, (str, Path)):
            raise ValueError(f"one alignment file for {len(paths)} inputs; give one per input or let each input "
                             "find its own <stem>.TextGrid / .lab")
        else:
            aligns = [alignment] * len(paths)
        parts = [read_corpus(p, format=fmt, rate=rate, alignment=a, **kw) for p, a in zip(paths, aligns)]
        return concat(parts)
    fn = _reader(fmt)
    params = inspect.signature(fn).parameters
    unknown = sorted(set(kw) - set(params))
    if unknown:
        takes = sorted(n for n, p in params.items() if p.kind == p.KEYWORD_ONLY or n in ("rate", "alignment", "tier"))
        raise TypeError(f"format {fmt!r} takes no option(s) {unknown}; it takes {takes}")
    c = fn(path, rate=rate, alignment=alignment, **kw)
    if c.point_roles is None and c.point_names:  # conventional sensor names (UL, LL, ML, JAW, REF, TT ...)
        from engine.recordings.layouts import guess_roles

        roles = guess_roles(c.point_names)
        if any(roles):
            c.point_roles = roles
    return c
