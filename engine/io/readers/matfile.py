"""A small, bounds-checked reader of MATLAB level-5 MAT-files.

``scipy.io.loadmat`` can crash the interpreter (segmentation fault) on damaged files;
this reader parses the format in Python with every size checked against the bytes
present, so a damaged file raises :class:`ImportFormatError` naming the byte offset.
It covers what articulography files hold: numeric, logical and char arrays, structs
and cells, compressed or not. Sparse arrays and objects are rejected.

Values: numeric / logical arrays as ndarrays of the stored shape; char arrays as str
(one row) or a list of str; structs as :class:`MatStruct`; cells as object ndarrays.

A compressed variable whose zlib stream lacks its end (the end-of-stream marker and the
Adler-32 checksum; a writer that stopped before closing the stream, or a file cut short
inside them) is read when every byte of the variable's data is still there: the reader
says so in ``notes`` (what was recovered, what could not be checked). When data bytes are
missing it is an error saying how many of the variable's bytes were recovered.
"""
from __future__ import annotations

import zlib
from pathlib import Path

import numpy as np

from engine.files.bounded import BINARY_EXPANSION
from engine.io._util import read_bytes
from engine.io.errors import ImportFormatError

__all__ = ["read_mat", "MatStruct"]

_MI = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 9: "f8", 12: "i8", 13: "u8",
       16: "u1", 17: "u2", 18: "u4"}  # 16-18: UTF-8/16/32 text
_MX_NUMERIC = {6: "f8", 7: "f4", 8: "i1", 9: "u1", 10: "i2", 11: "u2", 12: "i4", 13: "u4", 14: "i8", 15: "u8"}
MI_MATRIX, MI_COMPRESSED = 14, 15
MX_CELL, MX_STRUCT, MX_OBJECT, MX_CHAR, MX_SPARSE = 1, 2, 3, 4, 5
MAX_DEPTH = 32
MAX_INFLATE = 2 * 1024**3  # bytes one compressed variable may expand to
#: all compressed variables of one file together may expand to this many times the file size, plus 64 MiB
MAX_EXPANSION, EXPANSION_SLACK = 64, 64 * 1024**2


class MatStruct:
    """A MATLAB struct array: ``shape``, ``fields`` and one dict per element (column-major order)."""

    def __init__(self, shape, fields, elements):
        self.shape = tuple(shape)
        self.fields = list(fields)
        self.elements = list(elements)

    def __len__(self):
        return len(self.elements)

    def __getitem__(self, i):
        return self.elements[i]

    def __repr__(self):
        return f"MatStruct(shape={self.shape}, fields={self.fields})"


class _Reader:
    def __init__(self, path, endian, budget=MAX_INFLATE):
        self.path, self.e = path, endian
        self.budget = budget  # bytes all compressed variables may still expand to (zip bombs)
        self.notes = []  # damage found and what was recovered despite it

    def fail(self, offset, what):
        raise ImportFormatError(self.path, f"damaged MAT-file at byte {offset}: {what}")

    def tag(self, buf, pos, base, *, cut_ok=False):
        """(type, nbytes, data start, next element position).

        ``cut_ok``: a compressed element claiming more bytes than remain is returned with the
        bytes present (the caller says what was lost), instead of an error.
        """
        if pos + 8 > len(buf):
            self.fail(base + pos, f"a data element tag needs 8 bytes, {len(buf) - pos} remain")
        first = int(np.frombuffer(buf, self.e + "u4", 1, pos)[0])
        if first >> 16:  # small data element: size in the upper 16 bits, data in the tag
            mtype, n = first & 0xFFFF, first >> 16
            if n > 4:
                self.fail(base + pos, f"small data element claims {n} bytes (at most 4)")
            return mtype, n, pos + 4, pos + 8
        n = int(np.frombuffer(buf, self.e + "u4", 1, pos + 4)[0])
        start = pos + 8
        if start + n > len(buf) and cut_ok and first == MI_COMPRESSED:
            return first, len(buf) - start, start, len(buf)
        if start + n > len(buf):
            self.fail(base + pos, f"element of type {first} claims {n} bytes, {len(buf) - start} remain")
        nxt = start + n if first == MI_COMPRESSED else start + ((n + 7) // 8) * 8
        return first, n, start, min(nxt, len(buf))

    def numbers(self, buf, pos, base, what):
        mtype, n, start, nxt = self.tag(buf, pos, base)
        if mtype not in _MI:
            self.fail(base + pos, f"{what}: data type {mtype} is not a numeric MAT type")
        dt = np.dtype(self.e + _MI[mtype])
        if n % dt.itemsize:
            self.fail(base + pos, f"{what}: {n} bytes is not a whole number of {dt.itemsize}-byte values")
        return np.frombuffer(buf, dt, n // dt.itemsize, start), mtype, nxt

    def _unfinished(self, inner, offset, depth, cut):
        """(name, value) of a compressed variable whose zlib stream has no end; a note says what was recovered.

        ``cut``: bytes of the element the file lacks (it ends inside it), 0 when the element is whole.
        """
        where = (f"the file ends {cut:,} bytes before the end of the compressed element at byte {offset}" if cut
                 else f"the compressed element at byte {offset} stops before its end")
        need = self._inner_size(inner)
        name = self._inner_name(inner)
        what = f"variable {name!r}" if name else "a variable"
        try:
            name, value, _ = self.element(inner, 0, 0, depth + 1)
        except ImportFormatError:
            lost = f"{need - len(inner):,} of its {need:,} bytes are missing" if need else "its data is incomplete"
            self.fail(offset, f"{where}: its zlib stream lacks its end and {what} cannot be read: "
                      f"{len(inner):,} bytes were recovered, {lost}")
        extra = f", {len(inner) - need:,} bytes after it ignored" if need and len(inner) > need else ""
        self.notes.append(f"damaged MAT-file: {where}: its zlib stream lacks its end-of-stream marker and Adler-32 "
                          f"checksum; all {min(len(inner), need or len(inner)):,} bytes of {what} were recovered and "
                          f"read{extra}, but cannot be verified against the checksum")
        return name, value

    def _inner_size(self, inner) -> int:
        """Bytes the decompressed element's own tag says it takes (0 when not even its tag survived)."""
        if len(inner) < 8:
            return 0
        return 8 + int(np.frombuffer(inner, self.e + "u4", 1, 4)[0])

    def _inner_name(self, inner) -> str:
        """The array name of a decompressed miMATRIX element, or "" when it cannot be read."""
        if len(inner) < 8 or int(np.frombuffer(inner, self.e + "u4", 1, 0)[0]) != MI_MATRIX:
            return ""
        body = inner[8:8 + int(np.frombuffer(inner, self.e + "u4", 1, 4)[0])]  # what survived of it
        try:
            _, _, p = self.numbers(body, 0, 0, "array flags")
            _, _, p = self.numbers(body, p, 0, "dimensions")
            raw, _, _ = self.numbers(body, p, 0, "array name")
            return raw.astype(np.uint8).tobytes().decode("latin-1")
        except ImportFormatError:
            return ""

    def element(self, buf, pos, base, depth):
        """(name, value, next position) of the miMATRIX (or miCOMPRESSED) element at ``pos``."""
        if depth > MAX_DEPTH:
            self.fail(base + pos, f"arrays nested deeper than {MAX_DEPTH}")
        mtype, n, start, nxt = self.tag(buf, pos, base, cut_ok=depth == 0)
        if mtype == MI_COMPRESSED:
            claimed = int(np.frombuffer(buf, self.e + "u4", 1, pos + 4)[0])
            d = zlib.decompressobj()
            limit = max(1, min(MAX_INFLATE, self.budget))
            try:
                inner = d.decompress(buf[start:start + n], limit)
            except zlib.error as exc:
                self.fail(base + pos, f"compressed data is corrupt ({exc})")
            if d.unconsumed_tail:
                self.fail(base + pos, f"compressed data expands beyond {limit} bytes (at most {MAX_EXPANSION}x "
                          "the file size in all, 2 GiB per variable); refused as a decompression bomb")
            self.budget -= len(inner)
            if d.eof:
                name, value, _ = self.element(inner, 0, 0, depth + 1)
                return name, value, nxt
            return self._unfinished(inner, base + pos, depth, claimed - n) + (nxt,)
        if mtype != MI_MATRIX:
            self.fail(base + pos, f"expected a matrix (type 14), found data type {mtype}")
        if n == 0:
            return "", np.zeros((0, 0)), nxt
        body = buf[start:start + n]
        here = base + start
        flags, _, p = self.numbers(body, 0, here, "array flags")
        if flags.size < 2:
            self.fail(here, "array flags need 2 values")
        cls, complex_ = int(flags[0]) & 0xFF, bool(int(flags[0]) & 0x0800)
        logical = bool(int(flags[0]) & 0x0200)
        dims, _, p = self.numbers(body, p, here, "dimensions")
        if dims.size < 2 or (dims < 0).any():
            self.fail(here + p, f"dimensions {dims.tolist()}; expected at least 2 non-negative sizes")
        shape = tuple(int(x) for x in dims)
        count = int(np.prod(shape, dtype=np.float64))
        raw, _, p = self.numbers(body, p, here, "array name")
        name = raw.astype(np.uint8).tobytes().decode("latin-1")
        if cls in _MX_NUMERIC:
            vals, _, p = self.numbers(body, p, here, f"{name or 'array'} data")
            if vals.size != count:
                self.fail(here + p, f"{name or 'array'}: {vals.size} values for dimensions {shape}")
            out = vals.astype(np.bool_ if logical else _MX_NUMERIC[cls]).reshape(shape, order="F")
            if complex_:
                im, _, p = self.numbers(body, p, here, f"{name or 'array'} imaginary part")
                if im.size != count:
                    self.fail(here + p, f"{name}: imaginary part has {im.size} values for {shape}")
                out = out + 1j * im.astype(np.float64).reshape(shape, order="F")
            return name, out, nxt
        if cls == MX_CHAR:
            vals, mt, p = self.numbers(body, p, here, f"{name or 'char'} data")
            if mt == 16:  # UTF-8 bytes: decode, then lay the characters out like any char array
                text = vals.astype(np.uint8).tobytes().decode("utf-8", "replace")
                vals = np.array([ord(ch) for ch in text], dtype=np.int64)
            if vals.size != count:
                self.fail(here + p, f"{name or 'char'}: {vals.size} characters for dimensions {shape}")
            codes = vals.astype(np.int64).reshape(shape, order="F")
            rows = codes.reshape(shape[0], -1) if shape[0] else np.zeros((0, 0), np.int64)
            strs = ["".join(chr(c) if 0 <= c < 0x110000 else "\ufffd" for c in r) for r in rows]
            return name, (strs[0] if len(strs) == 1 else strs), nxt
        if cls == MX_CELL:
            if count * 8 > len(body) - p:
                self.fail(here + p, f"cell {name!r} of {shape} cannot fit in the {len(body) - p} bytes left")
            cells = np.empty(count, dtype=object)
            for k in range(count):
                if p >= len(body):
                    self.fail(here + p, f"cell {name!r} ends after {k} of {count} items")
                _, cells[k], p = self.element(body, p, here, depth + 1)
            return name, cells.reshape(shape, order="F"), nxt
        if cls in (MX_STRUCT, MX_OBJECT):
            if cls == MX_OBJECT:
                self.fail(here, f"{name!r} is a MATLAB object; expected plain structs and arrays")
            ln, _, p = self.numbers(body, p, here, "field name length")
            if ln.size != 1 or not 0 < int(ln[0]) <= 64:
                self.fail(here + p, f"field name length {ln.tolist()}; expected one value in 1..64")
            raw, _, p = self.numbers(body, p, here, "field names")
            width = int(ln[0])
            if raw.size % width:
                self.fail(here + p, f"{raw.size} bytes of field names is not a multiple of {width}")
            blob = raw.astype(np.uint8).tobytes()
            fields = [blob[i:i + width].split(b"\0", 1)[0].decode("latin-1") for i in range(0, len(blob), width)]
            if (fields and count * len(fields) * 8 > len(body) - p) or (not fields and count > 10**6):
                self.fail(here + p, f"struct {name!r} of {shape} with {len(fields)} fields cannot fit in the "
                          f"{len(body) - p} bytes left")
            elems = []
            for k in range(count):
                d = {}
                for f in fields:
                    if p >= len(body):
                        self.fail(here + p, f"struct {name!r} ends at element {k}, field {f!r}")
                    _, d[f], p = self.element(body, p, here, depth + 1)
                elems.append(d)
            return name, MatStruct(shape, fields, elems), nxt
        self.fail(here, f"{name!r} has MATLAB class {cls} (sparse, function handle, ...); not supported")


def read_mat(path, *, notes: list | None = None) -> dict:
    """The variables of a level-5 MAT-file, ``{name: value}``.

    Parameters
    ----------
    path : str or Path
    notes : list, optional
        Receives one sentence per damage the file survived (a compressed variable whose
        zlib stream lacks its end, every data byte present): what was recovered and what
        could not be checked. Callers put them in the corpus history.

    Raises :class:`ImportFormatError` (naming the byte offset) for anything damaged,
    truncated or of an unsupported kind (v4, v7.3/HDF5, sparse, objects); a compressed
    variable missing data bytes says how many were recovered.
    """
    path = Path(path)
    data = read_bytes(path, expansion=BINARY_EXPANSION)
    if len(data) < 128 or not data.startswith(b"MATLAB 5.0 MAT-file"):
        raise ImportFormatError(path, f"starts with {data[:20]!r}; expected a MATLAB 5 MAT-file "
                                "(v7.3/HDF5 files: re-save with save -v7)")
    mark = data[126:128]
    if mark not in (b"IM", b"MI"):
        raise ImportFormatError(path, f"endian indicator at byte 126 is {mark!r}; expected 'IM' or 'MI'")
    r = _Reader(path, "<" if mark == b"IM" else ">", budget=MAX_EXPANSION * len(data) + EXPANSION_SLACK)
    out, pos = {}, 128
    while pos < len(data):
        if len(data) - pos < 8 and not data[pos:].strip(b"\0"):
            break  # padding
        name, value, pos = r.element(data, pos, 0, 0)
        out[name] = value
    if notes is not None:
        notes.extend(r.notes)
    return out
