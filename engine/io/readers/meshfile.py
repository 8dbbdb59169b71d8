"""Single mesh files: Wavefront OBJ and Stanford PLY (ASCII and binary), read with numpy only.

Readers return ``(vertices (V, 3) float64, faces (F, 3) int64 or None)``; polygons are
split into triangle fans. The writers are :mod:`engine.io.writers.meshfile`.

The writers can label vertices (e.g. the articulograph sensors of a lip contour mesh),
``labels=[(name, vertex index 0-based), ...]``. OBJ: a ``# sensor <name> vertex <k>``
comment per label (``k`` 1-based, as OBJ indices are) before the vertices, the faces
in group ``g mesh``, then per label a group ``g <name>`` (whitespace in the name
replaced by ``_``) holding the point element ``p <k>``. PLY: a header line
``comment sensor <name> vertex <k>`` per label (``k`` 0-based, as PLY face indices
are). :func:`read_vertex_labels` reads them back from either format.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from engine._deprecated import deprecated_names
from engine.io._util import decode_text, read_bytes
from engine.io.errors import ImportFormatError

__all__ = ["read_obj", "read_ply", "read_mesh", "read_vertex_labels"]

# the writers moved to engine.io.writers.meshfile; this old home still gives them, with a warning
__getattr__ = deprecated_names(__name__, {name: ("engine.io.writers.meshfile", name)
                                          for name in ("write_obj", "write_ply", "write_mesh")})

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def _fan(poly):
    return [(poly[0], poly[k], poly[k + 1]) for k in range(1, len(poly) - 1)]


# ---------------------------------------------------------------------------- OBJ
def _read_obj_fast(lines):
    """Vectorised read of the common layout ('v x y z' lines, then 'f a b c' lines); None if not that."""
    vi = [i for i, s in enumerate(lines) if s[:2] == "v "]
    fi = [i for i, s in enumerate(lines) if s[:2] == "f "]
    if not vi or (fi and fi[0] < vi[-1]):
        return None
    fl = [lines[i] for i in fi]
    if any(len(s.split()) != 4 or "/" in s for s in fl):
        return None  # polygons or v/vt/vn indices: the line-by-line reader
    try:
        V = np.loadtxt([lines[i] for i in vi], usecols=(1, 2, 3), dtype=np.float64, ndmin=2, comments=None)
        F = np.loadtxt(fl, usecols=(1, 2, 3), dtype=np.int64, ndmin=2, comments=None) - 1 if fl else None
    except (ValueError, OverflowError):
        return None  # the line-by-line reader names the bad line
    if F is not None and (F.min() < 0 or F.max() >= len(V)):
        return None
    return V, F


def read_obj(path):
    """Vertices and triangles of a Wavefront OBJ file (``v`` and ``f`` records; others ignored).

    Returns
    -------
    vertices : ndarray of shape (V, 3) float64
    faces : ndarray of shape (F, 3) int64 (0-based), or None when the file has no faces
    """
    lines = decode_text(read_bytes(path), path).split("\n")
    fast = _read_obj_fast(lines)
    if fast is not None:
        return fast
    verts, faces = [], []
    for i, raw in enumerate(lines, start=1):
        if raw[:2] == "v " or raw[:2] == "v\t":
            tok = raw.split()
            if len(tok) < 4:
                raise ImportFormatError(path, f"vertex record {raw.strip()[:60]!r}; expected 'v x y z'", line=i)
            try:
                verts.append((float(tok[1]), float(tok[2]), float(tok[3])))
            except ValueError:
                raise ImportFormatError(path, f"vertex record {raw.strip()[:60]!r}; expected three numbers",
                                        line=i) from None
        elif raw[:2] == "f " or raw[:2] == "f\t":
            tok = raw.split()[1:]
            if len(tok) < 3:
                raise ImportFormatError(path, f"face record with {len(tok)} vertices; expected at least 3", line=i)
            poly = []
            for t in tok:
                try:
                    k = int(t.split("/", 1)[0])
                except ValueError:
                    raise ImportFormatError(path, f"face vertex {t[:30]!r}; expected an index like 5, 5/2 or "
                                            "5//1", line=i) from None
                k = k - 1 if k > 0 else len(verts) + k  # OBJ: 1-based, negative = relative
                if not 0 <= k < len(verts):
                    raise ImportFormatError(path, f"face vertex {t!r} refers to vertex {k + 1}; only "
                                            f"{len(verts)} vertices are defined so far", line=i)
                poly.append(k)
            faces.extend(_fan(poly))
    if not verts:
        raise ImportFormatError(path, "holds no vertices; expected 'v x y z' records (an OBJ mesh)")
    V = np.asarray(verts, dtype=np.float64)
    return V, (np.asarray(faces, dtype=np.int64) if faces else None)


# ---------------------------------------------------------------------------- PLY
def _ply_header(data: bytes, path):
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise ImportFormatError(path, f"starts with {data[:12]!r}; expected 'ply' ... 'end_header' (a PLY file)",
                                line=1)
    nl = data.find(b"\n", end)
    body = len(data) if nl < 0 else nl + 1
    lines = decode_text(data[:end], path).split("\n")
    elements: list[dict[str, Any]]
    fmt, elements = None, []
    for i, raw in enumerate(lines[1:], start=2):
        tok = raw.split()
        if not tok or tok[0] in ("comment", "obj_info"):
            continue
        if tok[0] == "format":
            if len(tok) < 2 or tok[1] not in ("ascii", "binary_little_endian", "binary_big_endian"):
                raise ImportFormatError(path, f"{raw.strip()[:60]!r}; expected 'format ascii|binary_little_endian|"
                                        "binary_big_endian 1.0'", line=i)
            fmt = tok[1]
        elif tok[0] == "element":
            try:
                n = int(tok[2])
                if n < 0:
                    raise ValueError
            except (IndexError, ValueError):
                raise ImportFormatError(path, f"{raw.strip()[:60]!r}; expected 'element <name> <count>'",
                                        line=i) from None
            elements.append({"name": tok[1], "count": n, "props": [], "line": i})
        elif tok[0] == "property":
            if not elements:
                raise ImportFormatError(path, "property before any element", line=i)
            if len(tok) == 5 and tok[1] == "list" and tok[2] in _PLY_TYPES and tok[3] in _PLY_TYPES:
                elements[-1]["props"].append((tok[4], _PLY_TYPES[tok[2]], _PLY_TYPES[tok[3]]))
            elif len(tok) == 3 and tok[1] in _PLY_TYPES:
                elements[-1]["props"].append((tok[2], _PLY_TYPES[tok[1]], None))
            else:
                raise ImportFormatError(path, f"{raw.strip()[:60]!r}; expected 'property <type> <name>' or "
                                        "'property list <count type> <index type> <name>'", line=i)
        else:
            raise ImportFormatError(path, f"unknown header line {raw.strip()[:60]!r}", line=i)
    if fmt is None:
        raise ImportFormatError(path, "the header has no 'format' line")
    return fmt, elements, body, len(lines) + 1


class _Ragged:
    """A list property of every row: ``counts`` (n,) and the items ``flat`` (counts.sum(),), int64."""

    __slots__ = ("counts", "flat")

    def __init__(self, counts, flat):
        self.counts, self.flat = counts, flat

    def __len__(self):
        return len(self.counts)


def _empty_columns(props):
    """The columns of an element of 0 rows: an empty :class:`_Ragged` per list property, else (0,)."""
    return {p[0]: (_Ragged(np.zeros(0, np.int64), np.zeros(0, np.int64)) if p[2] else np.zeros(0)) for p in props}


#: positions handled per pass of the binary row finder (its arrays are a few times this, int64)
_CHUNK = 1 << 20


def _gather(u8, starts, dt):
    """Values of dtype ``dt`` at the (unaligned) byte offsets ``starts`` of ``u8``.

    One zero-copy view of the buffer per byte phase (offset modulo the item size): a
    value at byte p is item p // size of the view starting at p % size.
    """
    k = dt.itemsize
    if k == 1:
        return u8[starts].view(dt)
    out = np.empty(len(starts), dt)
    phase = starts % k
    for o in range(k):
        sel = phase == o
        if sel.any():
            view = np.frombuffer(u8, dt, count=(len(u8) - o) // k, offset=o)
            out[sel] = view[starts[sel] // k]
    return out


def _row_lengths(u8, p, props, endian):
    """Byte length of a row starting at each offset in ``p``; -1 where it cannot be one."""
    off = np.zeros(len(p), np.int64)
    ok = np.ones(len(p), bool)
    for _, ct, it in props:
        ct_ = np.dtype(endian + ct)
        if it is None:
            off += ct_.itemsize
            continue
        at = p + off
        fits = ok & (at + ct_.itemsize <= len(u8))
        k = np.zeros(len(p), np.int64)
        k[fits] = _gather(u8, at[fits], ct_).astype(np.int64)
        ok &= fits & (k >= 0)
        off += ct_.itemsize + np.where(ok, k, 0) * np.dtype(it).itemsize
    return np.where(ok & (p + off <= len(u8)), off, -1)


def _binary_row_starts(el, u8, pos, endian, path):
    """Byte offsets of an element's ``n`` rows, whose lengths vary (list properties).

    Row r + 1 starts where row r ends, which depends on row r's list counts: a chain. It
    is followed without a Python loop per row: every byte offset of a window is given
    the offset of the row that would follow it (``next``), and the chain from the
    window's first row is read off by pointer doubling (rows 0..2^j-1 -> 0..2^(j+1)-1
    through next^(2^j)), O(window x log rows) in numpy.
    """
    n, props = el["count"], el["props"]
    starts = []
    have = 0
    while have < n:
        hi = min(len(u8), pos + _CHUNK)
        p = np.arange(pos, hi, dtype=np.int64)
        L = _row_lengths(u8, p, props, endian)
        if L[0] < 0:
            raise ImportFormatError(path, f"element {el['name']!r} row {have}: a list does not fit in the "
                                    f"{len(u8) - pos} bytes left (byte {pos}); truncated file?")
        W = hi - pos
        nxt = np.where(L > 0, np.arange(W) + L, W)  # local offsets; W = beyond this window
        J = np.append(np.minimum(nxt, W), W).astype(np.int32)  # int32: half the memory traffic per pass
        S = np.zeros(1, np.int32)
        while len(S) < n - have:
            T = J[S]
            T = T[T < W]
            if not T.size:
                break
            S = np.concatenate([S, T])
            J = J[J]
        S = S[: n - have]
        S = S.astype(np.int64)
        starts.append(S + pos)
        have += len(S)
        last = int(S[-1])
        if L[last] < 0:
            raise ImportFormatError(path, f"element {el['name']!r} row {have - 1}: a list does not fit in the "
                                    f"{len(u8) - pos - last} bytes left (byte {pos + last}); truncated file?")
        pos = pos + last + int(L[last])
        if have < n and pos >= len(u8):
            raise ImportFormatError(path, f"element {el['name']!r}: the data ends after {have} of its {n} rows "
                                    f"(byte {pos}); truncated file?")
    return np.concatenate(starts), pos


def _read_binary_element(el, buf, pos, endian, path):
    n, props = el["count"], el["props"]
    if all(p[2] is None for p in props):
        dt = np.dtype([(f"p{k}", endian + p[1]) for k, p in enumerate(props)])
        if pos + n * dt.itemsize > len(buf):
            raise ImportFormatError(path, f"element {el['name']!r}: the data ends before its {n} rows "
                                    f"({n * dt.itemsize} bytes from byte {pos}); truncated file?")
        rec = np.frombuffer(buf, dtype=dt, count=n, offset=pos)
        with np.errstate(invalid="ignore", over="ignore"):  # NaN payloads are caught later as non-finite
            cols = {p[0]: rec[f"p{k}"].astype(np.float64) for k, p in enumerate(props)}
        return cols, pos + n * dt.itemsize
    if n == 0:
        return _empty_columns(props), pos
    u8 = np.frombuffer(buf, np.uint8)
    if len(props) == 1:  # e.g. faces: one list; fast path when every row has the same length
        name, ct, it = props[0]
        ct_, it_ = np.dtype(endian + ct), np.dtype(endian + it)
        if pos + ct_.itemsize <= len(buf):
            k = int(np.frombuffer(buf, ct_, 1, pos)[0])
            dt = np.dtype([("n", ct_), ("i", it_, (k,))] if k > 0 else [("n", ct_)])
            if k >= 0 and pos + n * dt.itemsize <= len(buf):  # also empty lists: no row-by-row Python loop
                rec = np.frombuffer(buf, dtype=dt, count=n, offset=pos)
                if (rec["n"] == k).all():
                    lists = rec["i"].astype(np.int64) if k > 0 else np.zeros((n, 0), np.int64)
                    return {name: lists}, pos + n * dt.itemsize
    starts, end = _binary_row_starts(el, u8, pos, endian, path)
    cols, off = {}, np.zeros(n, np.int64)
    for name, ct, it in props:
        ct_ = np.dtype(endian + ct)
        vals = _gather(u8, starts + off, ct_)
        off += ct_.itemsize
        if it is None:
            with np.errstate(invalid="ignore", over="ignore"):
                cols[name] = vals.astype(np.float64)
            continue
        it_ = np.dtype(endian + it)
        k = vals.astype(np.int64)
        first = np.cumsum(k) - k
        item = np.repeat(starts + off, k) + (np.arange(int(k.sum())) - np.repeat(first, k)) * it_.itemsize
        cols[name] = _Ragged(k, _gather(u8, item, it_).astype(np.int64))
        off += k * it_.itemsize
    return cols, end


def _ascii_lines(data: bytes, body: int, body_line: int, path):
    """The body's non-blank lines: (byte start, byte end, tokens, line number) arrays, without
    splitting it into Python strings."""
    decode_text(data[body:], path)  # UTF-8 / NUL check, naming the line
    u8 = np.frombuffer(data, np.uint8, offset=body)
    nl = np.flatnonzero(u8 == 10)
    ends = np.append(nl, len(u8))
    begins = np.append(0, nl + 1)
    blank = (u8 == 32) | (u8 == 9) | (u8 == 13) | (u8 == 10)
    tok = ~blank & np.append(True, blank[:-1])  # a token starts after a blank or at the start
    ntok = np.add.reduceat(np.append(tok, False).view(np.uint8), begins, dtype=np.int64)  # per line
    keep = ntok > 0
    return (begins[keep] + body, ends[keep] + body, ntok[keep],
            np.flatnonzero(keep) + body_line)


def _ascii_numbers(data, a, b, count, dtype):
    """``count`` numbers of ``dtype`` parsed in C from ``data[a:b]``; None if it does not parse."""
    import warnings

    text = data[a:b].decode("ascii", "replace").replace("\r", " ")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy warns (not raises) on text it cannot read to its end
        try:
            vals = np.fromstring(text, dtype=dtype, sep=" ") if text.strip() else np.zeros(0, dtype)
        except (ValueError, DeprecationWarning):
            return None
    return vals if vals.size == count else None


def _read_ascii_element(el, data, lines, li, path):
    n, props = el["count"], el["props"]
    begins, ends, ntok, lineno = lines
    if li + n > len(begins):
        last = int(lineno[-1]) if len(lineno) else 0
        raise ImportFormatError(path, f"element {el['name']!r} declares {n} rows but only {len(begins) - li} "
                                "lines follow; truncated file?", line=last + 1)
    if n == 0:
        return _empty_columns(props), li
    rows = slice(li, li + n)
    a, b, counts = int(begins[rows][0]), int(ends[rows][-1]), ntok[rows]
    if all(p[2] is None for p in props):  # scalars only (vertices): one C parse
        if (counts == len(props)).all():
            vals = _ascii_numbers(data, a, b, n * len(props), np.float64)
            if vals is not None:
                arr = vals.reshape(n, len(props))
                return {p[0]: arr[:, k] for k, p in enumerate(props)}, li + n
    elif len(props) == 1:  # one list (faces): its count, then the items, one row per line
        vals = _ascii_numbers(data, a, b, int(counts.sum()), np.int64)
        if vals is not None:
            first = np.cumsum(counts) - counts
            k = vals[first]
            if (k == counts - 1).all():
                items = np.ones(len(vals), bool)
                items[first] = False
                return {props[0][0]: _Ragged(k, vals[items])}, li + n
    # something does not fit: the line-by-line reader names the first bad line
    cols = {p[0]: [] for p in props}
    for r in range(n):
        raw = data[int(begins[li + r]):int(ends[li + r])].decode("utf-8", "replace")
        tok, j = raw.split(), 0
        try:
            for name, _ct, it in props:
                if it is None:
                    cols[name].append(float(tok[j]))
                    j += 1
                else:
                    k = int(tok[j])
                    if k < 0 or j + 1 + k > len(tok):
                        raise IndexError
                    cols[name].append(np.array([int(t) for t in tok[j + 1:j + 1 + k]], np.int64))
                    j += 1 + k
            if j != len(tok):
                raise IndexError
        except (IndexError, ValueError, OverflowError):
            raise ImportFormatError(path, f"element {el['name']!r} row {r}: {raw.strip()[:60]!r}; "
                                    f"expected values for {[p[0] for p in props]}",
                                    line=int(lineno[li + r])) from None
    out = {}
    for name, _ct, it in props:
        if it is None:
            out[name] = np.asarray(cols[name], np.float64)
        else:
            k = np.array([len(x) for x in cols[name]], np.int64)
            out[name] = _Ragged(k, np.concatenate(cols[name]) if len(k) else np.zeros(0, np.int64))
    return out, li + n


def _triangles(lists, path) -> np.ndarray:
    """Triangle fans (F, 3) of a face list property: an (n, k) array or :class:`_Ragged`."""
    if isinstance(lists, np.ndarray):
        if lists.shape[1] < 3:
            raise ImportFormatError(path, f"faces have {lists.shape[1]} vertices; expected at least 3")
        return np.concatenate([lists[:, [0, k, k + 1]] for k in range(1, lists.shape[1] - 1)])
    k, flat = lists.counts, lists.flat
    short = np.flatnonzero(k < 3)
    if short.size:
        r = int(short[0])
        raise ImportFormatError(path, f"face {r} has {int(k[r])} vertices; expected at least 3"
                                + (f" ({short.size} faces have fewer than 3)" if short.size > 1 else ""))
    t = k - 2
    base = np.repeat(np.cumsum(k) - k, t)
    j = np.arange(int(t.sum())) - np.repeat(np.cumsum(t) - t, t) + 1
    return np.column_stack([flat[base], flat[base + j], flat[base + j + 1]])


def _counts(elements) -> str:
    return ", ".join(f"{e['name']} {e['count']}" for e in elements)


def read_ply(path):
    """Vertices and triangles of a PLY file (ASCII, binary little- or big-endian).

    Returns
    -------
    vertices : ndarray of shape (V, 3) float64
    faces : ndarray of shape (F, 3) int64, or None when the file has no faces
    """
    data = read_bytes(path)
    fmt, elements, body, body_line = _ply_header(data, path)
    got = {}
    if fmt == "ascii":
        lines = _ascii_lines(data, body, body_line, path)
        li = 0
        for el in elements:
            got[el["name"]], li = _read_ascii_element(el, data, lines, li, path)
        if li < len(lines[0]):  # the header's counts are smaller than the body
            raise ImportFormatError(path, f"{len(lines[0]) - li} more line(s) follow the rows the header's element "
                                    f"counts declare ({_counts(elements)}); "
                                    "expected the file to end (a damaged count?)", line=int(lines[3][li]))
    else:
        endian = "<" if fmt == "binary_little_endian" else ">"
        pos = body
        for el in elements:
            got[el["name"]], pos = _read_binary_element(el, data, pos, endian, path)
        if data[pos:].strip(b"\0\r\n\t "):  # padding aside, the header's counts are smaller than the body
            raise ImportFormatError(path, f"{len(data) - pos} bytes follow the rows the header's element counts "
                                    f"declare ({_counts(elements)}); "
                                    "expected the file to end (a damaged count?)")
    v = got.get("vertex")
    if v is None or not {"x", "y", "z"} <= set(v):
        raise ImportFormatError(path, "has no 'vertex' element with x, y, z properties; expected a PLY mesh "
                                "or point cloud")
    V = np.column_stack([np.asarray(v[a], np.float64) for a in "xyz"]).reshape(-1, 3)
    if V.shape[0] == 0:
        raise ImportFormatError(path, "has 0 vertices; expected at least one")
    faces = None
    f = got.get("face")
    if f is not None and len(f):
        key = "vertex_indices" if "vertex_indices" in f else ("vertex_index" if "vertex_index" in f else None)
        if key is None:
            raise ImportFormatError(path, f"the face element has {list(f)}; expected a 'vertex_indices' list")
        tris = _triangles(f[key], path)
        if tris.size and (tris.min() < 0 or tris.max() >= V.shape[0]):
            r = int(np.flatnonzero((tris < 0).any(1) | (tris >= V.shape[0]).any(1))[0])
            raise ImportFormatError(path, f"triangle {r} indexes vertex {tris[r].tolist()}; there are {V.shape[0]}")
        faces = tris if len(tris) else None
    return V, faces


def read_mesh(path):
    """:func:`read_obj` or :func:`read_ply` by content (``ply`` magic) or extension."""
    p = Path(path)
    with open(p, "rb") as fh:
        head = fh.read(3)
    return read_ply(p) if head == b"ply" or p.suffix.lower() == ".ply" else read_obj(p)


def read_vertex_labels(path) -> list[tuple[str, int]]:
    """The vertex labels a Lipspace writer put in an OBJ or PLY file: [(name, vertex index 0-based)]."""
    import re

    data = read_bytes(path)
    if Path(path).suffix.lower() == ".ply":
        end = data.find(b"end_header")
        if end < 0:
            raise ImportFormatError(path, "no 'end_header' line; expected a PLY header")
        text, pat, base = data[:end].decode("ascii", "replace"), r"^comment sensor (.+) vertex (\d+)\s*$", 0
    else:
        text, pat, base = decode_text(data, path), r"^# sensor (.+) vertex (\d+)\s*$", 1
    return [(m.group(1), int(m.group(2)) - base) for m in re.finditer(pat, text, flags=re.M)]
