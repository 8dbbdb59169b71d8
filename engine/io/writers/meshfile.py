"""Single mesh files written atomically: Wavefront OBJ and Stanford PLY (ASCII and binary), numpy only.

Vertices can be labelled (e.g. the articulograph sensors of a lip contour mesh),
``labels=[(name, vertex index 0-based), ...]``. OBJ: a ``# sensor <name> vertex <k>``
comment per label (``k`` 1-based, as OBJ indices are) before the vertices, the faces
in group ``g mesh``, then per label a group ``g <name>`` (whitespace in the name
replaced by ``_``) holding the point element ``p <k>``. PLY: a header line
``comment sensor <name> vertex <k>`` per label (``k`` 0-based, as PLY face indices
are). :func:`engine.io.readers.meshfile.read_vertex_labels` reads them back, and
:mod:`engine.io.readers.meshfile` the meshes.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from engine.files.atomic import atomic_write

__all__ = ["write_obj", "write_ply", "write_mesh"]


def _check(vertices, faces):
    V = np.asarray(vertices, dtype=np.float64)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ValueError(f"vertices must be (V, 3), got {V.shape}")
    F = None
    if faces is not None:
        F = np.asarray(faces, dtype=np.int64)
        if F.ndim != 2 or F.shape[1] != 3 or (F.size and (F.min() < 0 or F.max() >= V.shape[0])):
            raise ValueError(f"faces must be (F, 3) indices < {V.shape[0]}, got shape {F.shape}")
    return V, F


def _check_labels(labels, n_vertices):
    """``labels`` as a list of (name, 0-based index); ValueError naming the bad one."""
    out = []
    for j, item in enumerate(labels or ()):
        try:
            name, k = item
            k = int(k)
        except (TypeError, ValueError):
            raise ValueError(f"vertex label {j}: expected (name, vertex index), got {item!r}") from None
        name = str(name)
        if not name.strip() or any(c in name for c in "\r\n") or not name.isascii():
            raise ValueError(f"vertex label {j}: name {name!r} must be non-empty ASCII on one line")
        if not 0 <= k < n_vertices:
            raise ValueError(f"vertex label {j} ({name!r}): vertex {k} is outside 0..{n_vertices - 1}")
        out.append((name, k))
    return out


def write_obj(path, vertices, faces=None, *, labels=None, precision: int = 9) -> Path:
    """Write an OBJ file (``v`` records, ``f`` records when ``faces`` is given), atomically.

    ``labels`` : sequence of (name, vertex index 0-based), optional; see the module notes.
    """
    V, F = _check(vertices, faces)
    L = _check_labels(labels, len(V))
    fmt = f"%.{precision}g"
    with atomic_write(path) as tmp:
        with open(tmp, "w", encoding="ascii") as fh:
            fh.write("# written by Lipspace\n")
            fh.write("".join(f"# sensor {name} vertex {k + 1}\n" for name, k in L))
            fh.write((f"v {fmt} {fmt} {fmt}\n" * len(V)) % tuple(V.ravel().tolist()))
            if F is not None and len(F):
                if L:
                    fh.write("g mesh\n")
                fh.write(("f %d %d %d\n" * len(F)) % tuple((F + 1).ravel().tolist()))
            for name, k in L:
                fh.write(f"g {'_'.join(name.split())}\np {k + 1}\n")
    return Path(path)


def write_ply(path, vertices, faces=None, *, binary: bool = False, labels=None, precision: int = 9) -> Path:
    """Write a PLY file (float32 vertices, int32 triangle lists), ASCII or little-endian binary, atomically.

    ``labels`` : sequence of (name, vertex index 0-based), optional; see the module notes.
    """
    V, F = _check(vertices, faces)
    L = _check_labels(labels, len(V))
    head = ["ply", f"format {'binary_little_endian' if binary else 'ascii'} 1.0", "comment written by Lipspace",
            *(f"comment sensor {name} vertex {k}" for name, k in L), f"element vertex {len(V)}",
            "property float x", "property float y", "property float z"]
    if F is not None:
        head += [f"element face {len(F)}", "property list uchar int vertex_indices"]
    head.append("end_header")
    with atomic_write(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(("\n".join(head) + "\n").encode("ascii"))
            if binary:
                fh.write(V.astype("<f4").tobytes())
                if F is not None:
                    rec = np.empty(len(F), dtype=[("n", "u1"), ("i", "<i4", (3,))])
                    rec["n"], rec["i"] = 3, F
                    fh.write(rec.tobytes())
            else:
                fmt = f"%.{precision}g"
                text = (f"{fmt} {fmt} {fmt}\n" * len(V)) % tuple(V.ravel().tolist())
                if F is not None:
                    text += ("3 %d %d %d\n" * len(F)) % tuple(F.ravel().tolist())
                fh.write(text.encode("ascii"))
    return Path(path)


def write_mesh(path, vertices, faces=None, **kw) -> Path:
    """:func:`write_ply` for ``.ply`` paths, else :func:`write_obj`."""
    if Path(path).suffix.lower() == ".ply":
        return write_ply(path, vertices, faces, **kw)
    kw.pop("binary", None)
    return write_obj(path, vertices, faces, **kw)
