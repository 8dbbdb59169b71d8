"""Saving fitted engine objects as flat dicts of arrays (no pickle).

An estimator is saved as its constructor parameters (JSON) and its fitted
attributes (names ending in ``_``). Fitted attributes may be ndarrays, Python or
numpy scalars, strings, lists of str, ``scipy.sparse`` matrices or None. A class that sets
``_csr_on_use`` gets its csr attributes back as their saved arrays (``_csr_parts``) and makes each
matrix when it is first used: reading such an object imports no SciPy.

:func:`read_npz` reads a file's arrays, large ones memory-mapped where the archive
stores them uncompressed (as ``np.savez`` does): a manifold of ten million frames is
then paged in from disk as it is used, not copied into memory whole.
:func:`engine.files.mapped.release_pages` gives back the resident pages of such a map after a pass over it.
"""
from __future__ import annotations

import json
import os

import numpy as np

__all__ = ["dump_estimator", "load_estimator", "read_npz", "NpzReadError", "MMAP_MIN_BYTES"]

#: arrays of at least this many bytes are memory-mapped by ``read_npz(..., memory_map=None)``
MMAP_MIN_BYTES = 16 * 2**20


class NpzReadError(ValueError):
    """A file that is not a readable (pickle-free) ``.npz`` archive.

    ``path`` is the file and ``reason`` what stopped the read (exception type and text).
    """

    def __init__(self, path, reason: str):
        super().__init__(f"{path}: not a readable .npz file ({reason})")
        self.path, self.reason = path, reason


#: total uncompressed size allowed per .npz file: this many times the file size ...
MAX_EXPANSION = 64
#: ... plus this much (small archives of zeros compress very well)
EXPANSION_SLACK = 64 * 2**20


def read_npz(path, *, keys_only: bool = False, memory_map: bool | None = False):
    """Every array of the ``.npz`` file ``path`` as a dict (or only the set of its names).

    The file is opened here and always closed, also when it is empty, truncated or not
    a zip archive at all (numpy leaks its own handle in those cases). Nothing large is
    allocated before it is checked: only regular files are opened; the members'
    uncompressed sizes may total at most ``MAX_EXPANSION`` times the file size plus
    ``EXPANSION_SLACK`` (a zip bomb is refused before it is inflated); every array's
    header must declare no more bytes than its member holds; object arrays are refused.

    ``memory_map``: False reads every array into memory; None memory-maps (read-only
    ``np.memmap``) the arrays of at least :data:`MMAP_MIN_BYTES` that the archive stores
    uncompressed; True every such array. A compressed member is always read.

    Raises
    ------
    FileNotFoundError
        No such file.
    NpzReadError
        Anything else that stops the read, with the file name and the reason.
    """
    import zipfile

    from engine.files.validate import check_regular_file

    try:
        check_regular_file(path, ".npz file")
    except FileNotFoundError:
        raise
    except (OSError, ValueError) as exc:
        raise NpzReadError(path, str(exc).removeprefix(f"{path}: ")) from None
    try:
        with open(path, "rb") as fh, zipfile.ZipFile(fh) as zf:
            infos = [i for i in zf.infolist() if i.filename.endswith(".npy")]
            names = {i.filename[:-4] for i in infos}
            if keys_only:
                return names
            size = os.fstat(fh.fileno()).st_size
            total = sum(i.file_size for i in infos)
            cap = MAX_EXPANSION * size + EXPANSION_SLACK
            if total > cap:
                raise NpzReadError(path, f"its arrays would inflate to {total / 2**20:.0f} MiB from a "
                                         f"{size / 2**20:.1f} MiB file (limit {cap / 2**20:.0f} MiB); "
                                         "refused as a decompression bomb")
            least = None if memory_map is False else (0 if memory_map is True else MMAP_MIN_BYTES)
            return {i.filename[:-4]: _read_member(zf, i, path=path, fh=fh, size=size, mmap_least=least)
                    for i in infos}
    except (FileNotFoundError, NpzReadError):
        raise
    except MemoryError:
        raise NpzReadError(path, "not enough memory to load its arrays") from None
    except Exception as exc:  # BadZipFile, EOFError, OSError, ValueError (pickled data) ...
        raise NpzReadError(path, f"damaged or not an .npz archive ({exc})" if str(exc) else
                           "damaged or not an .npz archive") from None


def _read_member(zf, info, *, path=None, fh=None, size=0, mmap_least=None):
    """One ``.npy`` member, its header checked against the member's size first; memory-mapped when
    it is stored uncompressed and holds at least ``mmap_least`` bytes (None: never)."""
    import zipfile

    fmt = np.lib.format
    with zf.open(info) as f:
        version = fmt.read_magic(f)
        shape, fortran, dtype = (fmt.read_array_header_1_0(f) if version == (1, 0)
                                 else fmt.read_array_header_2_0(f))
        if dtype.hasobject:
            raise ValueError(f"array {info.filename[:-4]!r} holds Python objects (pickled data), refused")
        need = int(np.prod(shape, dtype=object)) * dtype.itemsize
        if need > info.file_size:
            raise ValueError(f"array {info.filename[:-4]!r} declares shape {shape} ({need} bytes) but its "
                             f"member holds {info.file_size} bytes")
        header = f.tell()  # bytes of the .npy header inside the member
    if (mmap_least is not None and len(shape) and need >= max(mmap_least, 1)
            and info.compress_type == zipfile.ZIP_STORED and fh is not None):
        start = _member_data(fh, info) + header
        if start + need <= size:
            return np.memmap(path, dtype=dtype, mode="r", offset=start, shape=tuple(shape),
                             order="F" if fortran else "C")
    with zf.open(info) as f:
        return fmt.read_array(f, allow_pickle=False)


def _member_data(fh, info) -> int:
    """Offset in the archive of member ``info``'s first byte (past its local file header)."""
    import struct

    fh.seek(info.header_offset)
    local = fh.read(30)
    if len(local) != 30 or local[:4] != b"PK\x03\x04":
        raise ValueError(f"member {info.filename!r}: bad local file header")
    name_len, extra_len = struct.unpack("<HH", local[26:30])
    return info.header_offset + 30 + name_len + extra_len


def _fitted_names(obj):
    """The fitted attributes of ``obj``: those set (names ending in ``_``) and the csr ones an object read
    from a file still holds as their saved arrays (see :func:`load_estimator`)."""
    names = [k for k in vars(obj) if k.endswith("_") and not k.startswith("_")]
    return names + [k for k in vars(obj).get("_csr_parts", {}) if k not in names]


def dump_estimator(obj, prefix: str) -> dict:
    """Flatten ``obj`` (a scikit-learn style estimator) to ``{prefix/...: array}``."""
    import scipy.sparse as sp

    out = {f"{prefix}/__class__": np.array(type(obj).__qualname__),
           f"{prefix}/__params__": np.array(json.dumps(obj.get_params(deep=False)))}
    kinds = {}
    for name in _fitted_names(obj):
        val = getattr(obj, name)
        key = f"{prefix}/{name}"
        if val is None:
            kinds[name] = "none"
        elif sp.issparse(val):
            m = sp.csr_matrix(val)
            out[key + ".data"], out[key + ".indices"], out[key + ".indptr"] = m.data, m.indices, m.indptr
            out[key + ".shape"] = np.array(m.shape)
            kinds[name] = "csr"
        elif isinstance(val, (list, tuple)) and all(isinstance(v, str) for v in val):
            out[key] = np.array(val, dtype=str)
            kinds[name] = "strlist"
        elif isinstance(val, str):
            out[key] = np.array(val)
            kinds[name] = "str"
        elif isinstance(val, (bool, np.bool_)):
            out[key] = np.array(bool(val))
            kinds[name] = "bool"
        elif isinstance(val, (int, np.integer)):
            out[key] = np.array(int(val))
            kinds[name] = "int"
        elif isinstance(val, (float, np.floating)):
            out[key] = np.array(float(val))
            kinds[name] = "float"
        elif isinstance(val, np.ndarray):
            if val.dtype == object:
                raise TypeError(f"{type(obj).__name__}.{name}: object arrays cannot be saved")
            out[key] = val
            kinds[name] = "array"
        else:
            raise TypeError(f"{type(obj).__name__}.{name}: cannot save a {type(val).__name__}")
    out[f"{prefix}/__kinds__"] = np.array(json.dumps(kinds))
    return out


_SCALAR = {"int": "int", "float": "float", "bool": "bool", "str": "str"}
_KNOWN_KINDS = ("none", "csr", "strlist", "str", "bool", "int", "float", "array")


def load_estimator(cls, d, prefix: str, *, source="<arrays>", schema=None, dims=None):
    """Rebuild an estimator of class ``cls`` from :func:`dump_estimator` output, checked.

    Parameters
    ----------
    cls : type
    d : mapping of str to ndarray
        The arrays of the file.
    prefix : str
    source : str or Path
        The file, for messages.
    schema : dict or None
        ``{attribute: spec}`` of the fitted attributes the caller relies on; a spec is a
        dict with ``kind`` (as saved: "array", "csr", "int", "float", "bool", "str",
        "strlist"), and for arrays ``dtype`` ("float", "int", "bool"), ``shape`` (symbols
        as in :func:`engine.files.validate.check_array`), ``low``/``high`` (value range; a
        str ``high`` is a symbol), ``none=True`` if None is allowed. Every attribute in
        the schema must be present; attributes outside it are checked generically
        (plain dtype, finite).
    dims : dict or None
        Symbol table shared with the caller's other checks (updated in place).

    Raises
    ------
    engine.files.validate.FieldError
        A missing or malformed field, naming the file and the field.
    """
    from engine.files.validate import FieldError, check_array, check_csr, check_scalar, json_field, parse_params

    dims = {} if dims is None else dims
    schema = schema or {}
    if f"{prefix}/__params__" not in d or f"{prefix}/__kinds__" not in d:
        raise FieldError(source, f"{prefix}/__params__", f"no saved {cls.__name__} in this file")
    params = check_scalar(d, f"{prefix}/__params__", source=source, kind="str")
    obj = parse_params(cls, params, source=source, field=f"{prefix}/__params__")
    kinds_text = check_scalar(d, f"{prefix}/__kinds__", source=source, kind="str")
    kinds = json_field(kinds_text, source=source, field=f"{prefix}/__kinds__")
    if not isinstance(kinds, dict) or not all(isinstance(v, str) for v in kinds.values()):
        raise FieldError(source, f"{prefix}/__kinds__", "expected a JSON object of attribute kinds")
    missing = sorted(set(schema) - set(kinds))
    if missing:
        raise FieldError(source, f"{prefix}/__kinds__", f"fitted attribute(s) {missing} missing")
    order = [n for n in schema if n in kinds] + [n for n in kinds if n not in schema]
    for name in order:  # the schema's order: symbols are bound before ranges use them
        kind, key = kinds[name], f"{prefix}/{name}"
        if not (name.isidentifier() and name.endswith("_") and not name.startswith("_")):
            raise FieldError(source, key, "not a fitted-attribute name")
        if kind not in _KNOWN_KINDS:
            raise FieldError(source, key, f"unknown kind {kind!r}; expected one of {_KNOWN_KINDS}")
        spec = schema.get(name, {})
        want = spec.get("kind")
        if want is not None and kind != want and not (kind == "none" and spec.get("none")):
            raise FieldError(source, key, f"expected a saved {want}, got {kind}")
        if kind == "none":
            val = None
        elif kind == "csr":
            data, ind, ptr, shape = check_csr(d, key, source=source, shape=spec.get("shape", ("_r", "_c")),
                                              dims=dims if spec else {}, kind=spec.get("dtype", "number"),
                                              low=spec.get("low"))
            if getattr(cls, "_csr_on_use", False):  # the class makes the matrix on first use (no SciPy yet)
                obj.__dict__.setdefault("_csr_parts", {})[name] = (data, ind, ptr, tuple(shape))
                continue
            import scipy.sparse as sp

            val = sp.csr_matrix((data, ind, ptr), shape=shape)
        elif kind == "strlist":
            val = [str(s) for s in check_array(d, key, source=source, kind="str", shape=("_n",), dims={})]
        elif kind in _SCALAR:
            val = check_scalar(d, key, source=source, kind=_SCALAR[kind], low=spec.get("low"),
                               high=_high(spec, dims))
        else:
            val = check_array(d, key, source=source, kind=spec.get("dtype", "number"), shape=spec.get("shape"),
                              dims=dims, low=spec.get("low"), high=_high(spec, dims))
            if val.dtype.kind not in "fiub":
                raise FieldError(source, key, f"expected a numeric array, got {val.dtype}")
        setattr(obj, name, val)
    return obj


def _high(spec, dims):
    high = spec.get("high")
    if isinstance(high, str):
        return dims[high]  # a schema lists the attribute binding a symbol before its users
    return high


def source_fingerprint(modules, extra=None) -> str:
    """A short hash of the source code of ``modules`` (dotted names) and ``extra`` (JSON-able).

    Caches key their entries on it, so a result computed by older code or with other
    parameters is never reused: any edit to an algorithm's module changes the key
    (no version number to forget to bump).
    """
    import hashlib
    import importlib.util

    h = hashlib.sha256()
    for name in sorted(modules):
        spec = importlib.util.find_spec(name)
        origin = getattr(spec, "origin", None)
        h.update(name.encode())
        if origin and os.path.isfile(origin):
            with open(origin, "rb") as fh:
                h.update(fh.read())
    h.update(json.dumps(extra, sort_keys=True, default=str).encode())
    return h.hexdigest()[:16]
