"""Checks for arrays and settings read back from files (manifold, corpus, session).

A file read from disk is untrusted: every array is checked for its kind (float, int,
bool, str), shape, finiteness and index range before any engine code uses it, and
every saved parameter set is parsed against the estimator's own parameters (unknown
keys and wrong types refused). Failures raise :class:`FieldError`, a ``ValueError``
whose message names the file, the field, what was expected and what was found; the
loaders turn it into their own error type (``ManifoldFileError``, ``CorpusError``).

Also here: :func:`check_regular_file` (FIFOs, devices and directories are refused
before anything opens them) and :func:`check_source_path` for paths named inside
session files.
"""
from __future__ import annotations

import math
import os
import stat
from pathlib import Path

import numpy as np

from engine.files.mapped import release_pages

__all__ = ["FieldError", "check_array", "check_scalar", "check_csr", "parse_params",
           "check_regular_file", "check_source_path", "check_inside", "wav_info", "json_field", "DATA_SUFFIXES"]

#: suffixes of the data files a session may name as its source
DATA_SUFFIXES = (".npz", ".mat", ".ema", ".c3d", ".csv", ".tsv", ".txt", ".npy", ".pos")

#: dtype kinds per expected family; complex values are never a coordinate (a complex embedding is refused)
_KINDS = {"float": "f", "int": "iu", "bool": "b", "str": "U", "number": "fiub"}


class FieldError(ValueError):
    """One field of a file does not hold what it must; the message says which and why."""

    def __init__(self, source, field: str, problem: str):
        super().__init__(f"{source}: field {field!r}: {problem}")
        self.source, self.field, self.problem = source, field, problem


def _describe(a) -> str:
    return f"a {a.dtype} array of shape {a.shape}" if isinstance(a, np.ndarray) else f"a {type(a).__name__}"


def _resolve(sym, dims: dict, source, field):
    """An expected axis length: an int, a symbol (bound on first use) or '<n><symbol>'."""
    if isinstance(sym, int):
        return sym
    mult = 1
    if sym[0].isdigit():
        i = len(sym) - len(sym.lstrip("0123456789"))
        mult, sym = int(sym[:i]), sym[i:]
    if sym not in dims:
        return None
    return mult * dims[sym]


def check_array(d, key, *, source, kind="float", shape=None, dims=None, low=None, high=None,
                finite=True, field=None):
    """``d[key]`` as an ndarray after checking it.

    Parameters
    ----------
    d : mapping of str to ndarray
    key : str
    source : str or Path
        The file, for messages.
    kind : {"float", "int", "bool", "str", "number"}
        Allowed dtype family ("number": any of float/int/bool).
    shape : tuple of (int or str) or None
        Expected shape; str entries are symbols resolved in / bound into ``dims``
        ("2m" means twice the length bound to "m").
    dims : dict or None
        Symbol table shared by the checks of one file (updated in place).
    low, high : number or None
        Inclusive lower and exclusive upper bound of every value (index ranges).
    finite : bool
        Refuse NaN/inf in float arrays.
    """
    field = field or key
    if key not in d:
        raise FieldError(source, field, "missing")
    a = d[key]
    if not isinstance(a, np.ndarray) or a.dtype.kind not in _KINDS[kind]:
        raise FieldError(source, field, f"expected {kind} values, got {_describe(a)}")
    if shape is not None:
        dims = {} if dims is None else dims
        if a.ndim != len(shape):
            raise FieldError(source, field, f"expected {len(shape)} dimensions {tuple(shape)}, got shape {a.shape}")
        for axis, (sym, n) in enumerate(zip(shape, a.shape)):
            want = _resolve(sym, dims, source, field)
            if want is None:
                dims[sym] = int(n)
            elif n != want:
                raise FieldError(source, field, f"axis {axis} ({sym}) has length {n}, expected {want} "
                                                "(the file's arrays do not fit together)")
    mapped = isinstance(a, np.memmap)  # a pass over a memory-mapped array gives its pages back as it goes
    step = max(1, 2**22 // max(1, a[0].size if a.ndim and a.shape[0] else 1))  # rows per check
    if a.size and a.dtype.kind in "fc" and finite:
        for s in range(0, a.shape[0] if a.ndim else 1, step):  # no full-size bool copy
            part = a[s:s + step] if a.ndim else a
            ok = bool(np.isfinite(part).all())
            if not ok:
                where = np.argwhere(~np.isfinite(part))[0]
                where = (where[0] + s, *where[1:]) if a.ndim else ()
                raise FieldError(source, field, f"holds NaN/inf (first at index {tuple(int(i) for i in where)})")
            if mapped:
                release_pages(part)
    if a.size and (low is not None or high is not None) and a.dtype.kind in "fiub":
        if mapped and a.ndim:
            parts = [a[s:s + step] for s in range(0, a.shape[0], step)]
            lo, hi = min(p.min() for p in parts), max(p.max() for p in parts)
            for p in parts:
                release_pages(p)
        else:
            lo, hi = a.min(), a.max()
        if low is not None and lo < low:
            raise FieldError(source, field, f"value {lo} is below the allowed minimum {low}")
        if high is not None and hi >= high:
            raise FieldError(source, field, f"value {hi} is out of range (must be < {high})")
    return a


def check_scalar(d, key, *, source, kind="int", low=None, high=None, field=None):
    """``d[key]``, a 0-d array, as a Python int / float / bool / str after checking it."""
    a = check_array(d, key, source=source, kind=kind, shape=(), low=low, high=high, field=field)
    return {"float": float, "int": int, "bool": bool, "str": str, "number": float}[kind](a[()])


def check_csr(d, prefix, *, source, shape, dims, kind="number", low=None):
    """Check the arrays of a saved CSR matrix (``prefix.data/.indices/.indptr/.shape``).

    Index arrays must be integers, ``indptr`` start at 0, never decrease and end at
    ``len(indices) == len(data)``, and every column index lie in ``[0, n_cols)`` —
    scipy's compiled graph routines read out of bounds otherwise.

    Returns
    -------
    data, indices, indptr : ndarray
    shape : tuple of int
    """
    shp = check_array(d, prefix + ".shape", source=source, kind="int", shape=(2,), low=0)
    n_rows, n_cols = (int(s) for s in shp)
    for axis, sym in enumerate(shape):
        want = _resolve(sym, dims, source, prefix)
        if want is None:
            dims[sym] = (n_rows, n_cols)[axis]
        elif (n_rows, n_cols)[axis] != want:
            raise FieldError(source, prefix + ".shape", f"{(n_rows, n_cols)} does not fit {sym}={want}")
    ind = check_array(d, prefix + ".indices", source=source, kind="int", shape=("_nnz",), dims={}, low=0,
                      high=max(n_cols, 0) if n_cols > 0 else 0)
    ptr = check_array(d, prefix + ".indptr", source=source, kind="int", shape=(n_rows + 1,))
    data = check_array(d, prefix + ".data", source=source, kind=kind, shape=(len(ind),), low=low)
    if n_cols == 0 and len(ind):
        raise FieldError(source, prefix + ".indices", "entries in a matrix without columns")
    if ptr[0] != 0 or ptr[-1] != len(ind) or (len(ptr) > 1 and np.any(np.diff(ptr) < 0)):
        raise FieldError(source, prefix + ".indptr", f"must rise from 0 to {len(ind)} (the number of "
                                                     f"stored entries) without decreasing")
    return data, ind, ptr, (n_rows, n_cols)


def json_field(text, *, source, field):
    """The JSON a file's field ``field`` holds; :class:`FieldError` for anything that is not JSON, also
    nesting deep enough to exhaust Python's recursion (``[[[[...`` 100,000 deep)."""
    from engine.files.bounded import parse_json

    if not isinstance(text, (str, bytes)):
        raise FieldError(source, field, f"expected JSON text, got {type(text).__name__}")
    try:
        return parse_json(text, source=source)
    except ValueError as exc:
        raise FieldError(source, field, str(exc).removeprefix(f"{source}: ")) from None


def _param_ok(value, default) -> bool:
    if value is None:
        return True  # every estimator parameter with a None meaning defaults to None or accepts it
    if isinstance(value, float) and not math.isfinite(value):
        return False
    if isinstance(default, bool) or isinstance(value, bool):
        return isinstance(value, bool) and (default is None or isinstance(default, bool))
    if isinstance(default, int):
        return isinstance(value, int)
    if isinstance(default, float):
        return isinstance(value, (int, float))
    if isinstance(default, str):
        return isinstance(value, str)
    return isinstance(value, int)  # default None: a count (n_states, n_landmarks) or None


def parse_params(cls, text, *, source, field):
    """The constructor parameters of ``cls`` saved as JSON ``text``, checked.

    Must be a JSON object whose keys are parameters of ``cls`` (unknown keys refused)
    and whose values are plain scalars of the default's type (int where the default
    is an int, a number for a float, a string for a string; None is always allowed)
    that the class's declared constraints accept (``_parameter_constraints``, see
    :mod:`engine.constraints`). Missing keys take the default.
    """
    from engine.constraints import InvalidParameterError, validate_params

    params = json_field(text, source=source, field=field)
    if not isinstance(params, dict):
        raise FieldError(source, field, f"expected a JSON object of {cls.__name__} parameters, "
                                        f"got a {type(params).__name__}")
    defaults = cls().get_params(deep=False)
    unknown = sorted(set(params) - set(defaults))
    if unknown:
        raise FieldError(source, field, f"unknown {cls.__name__} parameter(s) {unknown}; "
                                        f"known: {sorted(defaults)}")
    for k, v in params.items():
        if not _param_ok(v, defaults[k]):
            want = type(defaults[k]).__name__ if defaults[k] is not None else "an int or null"
            raise FieldError(source, f"{field}.{k}", f"expected {want}, got {v!r}")
    obj = cls(**params)
    try:
        validate_params(obj)
    except InvalidParameterError as exc:
        raise FieldError(source, f"{field}.{exc.parameter}", exc.describe(fix=False)) from None
    return obj


def check_regular_file(path, what: str = "file") -> Path:
    """``path`` if it names an existing regular file; otherwise ``FileNotFoundError`` /
    ``IsADirectoryError`` / ``ValueError`` (FIFOs, sockets, devices would block or
    never end when read)."""
    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such {what}") from None
    if stat.S_ISDIR(st.st_mode):
        raise IsADirectoryError(f"{path}: is a directory, not a {what}")
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"{path}: not a regular file (a pipe, socket or device); give a {what} on disk")
    return path


def check_source_path(value, *, source, field="source.path", suffixes=DATA_SUFFIXES) -> Path:
    """A data-file path named inside a (session) file, checked before anything opens it.

    It must be a string naming an existing regular file with one of ``suffixes``
    (Lipspace corpus/manifold files and the formats the importers read). Relative
    paths are taken relative to the directory of ``source``. Anything else — a
    non-string, ``/etc/passwd``, a FIFO, a directory — raises :class:`FieldError`
    without the file having been opened, so no content of it can be shown.
    """
    if not isinstance(value, str) or not value or "\x00" in value:
        raise FieldError(source, field, f"expected a file name (string), got {value!r}"[:200])
    p = Path(value)
    if not p.is_absolute():
        p = Path(source).resolve().parent / p
    if p.suffix.lower() not in suffixes:
        raise FieldError(source, field, f"{p} is not a Lipspace data file (suffix must be one of "
                                        f"{', '.join(suffixes)})")
    try:
        return check_regular_file(p, "data file")
    except (OSError, ValueError) as exc:
        raise FieldError(source, field, str(exc)) from None


def check_corpus_arrays(d, *, source, frames_given: bool = False) -> None:
    """Check the arrays of a native corpus file (``Corpus.to_arrays``) before use.

    Dtypes and shapes that fit together (U utterances, P phones, N frames), phone
    utterance numbers < U, finite numbers. The corpus's own invariants (contiguous
    utterances, phones inside them, ...) are checked afterwards by ``Corpus.validate``.
    Raises :class:`FieldError`.
    """
    dims: dict = {}
    if "corpus_version" not in d:
        raise FieldError(source, "corpus_version", "missing (not a Lipspace corpus file)")
    check_scalar(d, "corpus_version", source=source, kind="int", low=1)
    check_scalar(d, "corpus_rate", source=source, kind="number")
    check_scalar(d, "corpus_dims", source=source, kind="int")
    check_scalar(d, "corpus_name", source=source, kind="str")
    check_array(d, "corpus_utt_ids", source=source, kind="str", shape=("U",), dims=dims)
    check_array(d, "corpus_utt_bounds", source=source, kind="int", shape=("U", 2), dims=dims, low=0)
    check_array(d, "corpus_utt_audio", source=source, kind="str", shape=("U",), dims=dims)
    check_array(d, "corpus_utt_text", source=source, kind="str", shape=("U",), dims=dims)
    check_array(d, "corpus_phone_utt", source=source, kind="int", shape=("P",), dims=dims, low=0, high=dims["U"])
    check_array(d, "corpus_phone_times", source=source, kind="float", shape=("P", 2), dims=dims)
    check_array(d, "corpus_phone_labels", source=source, kind="str", shape=("P",), dims=dims)
    if not frames_given:
        # finiteness is checked (naming frame and column) by Corpus.validate: one pass is enough
        check_array(d, "corpus_frames", source=source, kind="number", shape=("N", "C"), dims=dims, finite=False)
    if "corpus_faces" in d:
        check_array(d, "corpus_faces", source=source, kind="int", shape=("_f", 3), dims=dims, low=0)
    if "corpus_point_names" in d:
        check_array(d, "corpus_point_names", source=source, kind="str", shape=("_v",), dims=dims)
    if "corpus_utt_speaker" in d:
        check_array(d, "corpus_utt_speaker", source=source, kind="str", shape=("U",), dims=dims)
    if "corpus_utt_duration" in d:
        check_array(d, "corpus_utt_duration", source=source, kind="float", shape=("U",), dims=dims, low=0)
    if "corpus_axes" in d:
        check_scalar(d, "corpus_axes", source=source, kind="str")
    if "corpus_units" in d:
        check_scalar(d, "corpus_units", source=source, kind="str")
    if "corpus_utt_audio_abs" in d:
        check_array(d, "corpus_utt_audio_abs", source=source, kind="str", shape=("U",), dims=dims)
    for key in d:
        if key.startswith("corpus_latent_"):
            a = check_array(d, key, source=source, kind="number")
            if a.ndim not in (1, 2):
                raise FieldError(source, key, f"expected one value (or row) per frame, got shape {a.shape}")


def check_inside(value, base, *, source, field) -> Path:
    """A path stored in the file ``source`` (relative to the folder ``base``, or absolute), checked to stay
    inside ``base``: ``../private/secret.txt`` or ``/etc/passwd`` stored in a corpus never leads Lipspace
    out of the corpus's folder (symbolic links resolved). Raises :class:`FieldError` naming the path."""
    if not isinstance(value, str) or not value or "\x00" in value:
        raise FieldError(source, field, f"expected a file name, got {value!r}"[:200])
    base = Path(os.path.realpath(base))
    p = Path(value)
    real = Path(os.path.realpath(p if p.is_absolute() else base / p))
    if real != base and base not in real.parents:
        raise FieldError(source, field, f"{value} is outside the folder of {Path(source).name} ({base}); a path "
                                        "stored in a file is followed only inside its own folder")
    return real


#: WAV format tags: PCM, IEEE float, extensible
_WAV_FORMATS = {1: "PCM", 3: "float", 0xFFFE: "extensible"}


def wav_info(path) -> dict:
    """The header of the WAV file ``path`` (``rate``, ``channels``, ``bits``, ``seconds``), checked.

    Only the first 64 kB are read. ``ValueError`` naming the file when it is not a RIFF/WAVE file
    with a sound format (PCM or float), a plausible rate and a data chunk: a text file named
    ``.wav`` is never copied as the recording's sound.
    """
    import struct

    from engine.files.bounded import check_bounded

    path = Path(path)
    size = check_bounded(path, what="audio file")
    with open(path, "rb") as fh:
        head = fh.read(65536)
    if len(head) < 12 or head[:4] not in (b"RIFF", b"RF64") or head[8:12] != b"WAVE":
        raise ValueError(f"{path}: not a WAV file (it starts with {head[:12]!r}); expected a RIFF/WAVE sound file")
    pos, fmt, data = 12, None, None
    while pos + 8 <= len(head) and (fmt is None or data is None):
        cid, n = head[pos:pos + 4], struct.unpack("<I", head[pos + 4:pos + 8])[0]
        if cid == b"fmt " and n >= 16 and pos + 24 <= len(head):
            fmt = struct.unpack("<HHIIHH", head[pos + 8:pos + 24])
        elif cid == b"data":
            data = min(n, max(size - pos - 8, 0))
        pos += 8 + n + (n & 1)
    if fmt is None or data is None:
        raise ValueError(f"{path}: a RIFF/WAVE file without {'a format' if fmt is None else 'a data'} chunk; "
                         "expected sound")
    tag, channels, rate, _, block, bits = fmt
    if tag not in _WAV_FORMATS or not 1 <= channels <= 64 or not 1 <= rate <= 10**6 or \
            bits not in (8, 16, 24, 32, 64) or block == 0:
        raise ValueError(f"{path}: WAV format {tag}, {channels} channels, {rate} Hz, {bits} bits is not sound "
                         "Lipspace can use; expected PCM or float samples")
    return {"rate": rate, "channels": channels, "bits": bits, "format": _WAV_FORMATS[tag],
            "seconds": data / block / rate}
