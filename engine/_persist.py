"""Saving fitted engine objects as flat dicts of arrays (no pickle).

An estimator is saved as its constructor parameters (JSON) and its fitted
attributes (names ending in ``_``). Fitted attributes may be ndarrays, Python or
numpy scalars, strings, lists of str, ``scipy.sparse`` matrices or None.
"""
from __future__ import annotations

import json

import numpy as np
import scipy.sparse as sp

__all__ = ["dump_estimator", "load_estimator", "read_npz", "NpzReadError"]


class NpzReadError(ValueError):
    """A file that is not a readable (pickle-free) ``.npz`` archive.

    ``path`` is the file and ``reason`` what stopped the read (exception type and text).
    """

    def __init__(self, path, reason: str):
        super().__init__(f"{path}: not a readable .npz file ({reason})")
        self.path, self.reason = path, reason


def read_npz(path, *, keys_only: bool = False):
    """Every array of the ``.npz`` file ``path`` as a dict (or only the set of its names).

    The file is opened here and always closed, also when it is empty, truncated or not
    a zip archive at all (numpy leaks its own handle in those cases).

    Raises
    ------
    FileNotFoundError
        No such file.
    NpzReadError
        Anything else that stops the read, with the file name and the reason.
    """
    try:
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            return set(z.files) if keys_only else {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise
    except Exception as exc:  # BadZipFile, EOFError, OSError, ValueError (pickled data) ...
        raise NpzReadError(path, f"{type(exc).__name__}: {exc}") from None


def _fitted_names(obj):
    return [k for k in vars(obj) if k.endswith("_") and not k.startswith("_")]


def dump_estimator(obj, prefix: str) -> dict:
    """Flatten ``obj`` (a scikit-learn style estimator) to ``{prefix/...: array}``."""
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


def load_estimator(cls, d, prefix: str):
    """Rebuild an estimator of class ``cls`` from :func:`dump_estimator` output."""
    try:
        params = json.loads(str(d[f"{prefix}/__params__"]))
        kinds = json.loads(str(d[f"{prefix}/__kinds__"]))
    except KeyError:
        raise ValueError(f"no saved {cls.__name__} under {prefix!r} in this file") from None
    obj = cls(**params)
    for name, kind in kinds.items():
        key = f"{prefix}/{name}"
        if kind == "none":
            val = None
        elif kind == "csr":
            val = sp.csr_matrix((d[key + ".data"], d[key + ".indices"], d[key + ".indptr"]),
                               shape=tuple(int(s) for s in d[key + ".shape"]))
        elif kind == "strlist":
            val = [str(s) for s in d[key]]
        elif kind == "str":
            val = str(d[key])
        elif kind == "bool":
            val = bool(d[key])
        elif kind == "int":
            val = int(d[key])
        elif kind == "float":
            val = float(d[key])
        else:
            val = np.asarray(d[key])
        setattr(obj, name, val)
    return obj
