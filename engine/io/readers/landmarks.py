"""CSV landmark tracks: OpenFace output, Lipspace's own trajectory CSV, and a long
``frame,point,x,y[,z]`` table.

Layouts (the header row decides; names are matched case-sensitively for OpenFace's
``x_i``/``X_i`` and case-insensitively otherwise):

* **OpenFace**: columns ``x_0..x_67``, ``y_0..y_67`` (image pixels) and optionally
  ``X_0..``, ``Y_0..``, ``Z_0..`` (mm, camera space); ``timestamp``, ``frame``,
  ``face_id``, ``success`` are used when present (rows with ``success`` 0 are gaps).
* **Named wide**: ``<name>_x``, ``<name>_y`` [, ``<name>_z``] per point (what
  :func:`engine.io.writers.export.write_trajectory_csv` writes for frames).
* **Long**: one row per (frame, point): a ``frame`` or ``time`` column, a ``point`` (or
  ``landmark``/``marker``/``name``) column and ``x``, ``y`` [, ``z``].

Times (``time``, ``timestamp``, ``t``, ``seconds``) give the rate unless ``rate`` is passed;
values are kept in the file's units. Empty cells, ``nan`` and unsuccessful rows are gaps,
interpolated (or an error with ``fill_gaps=False``).
"""
from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np

from engine.io._util import decode_text, one_utterance_corpus, plausible_rate, read_bytes, sidecar_audio, uniform_rate
from engine.io._util import fill_gaps as _fill_gaps
from engine.io.errors import ImportFormatError
from engine.io.readers.alignment import resolve_alignment
from engine.io.repairs import reports_repairs

__all__ = ["read_csv_landmarks", "IBUG68_LIPS"]

#: the mouth landmarks of the 68-point iBUG / OpenFace scheme (outer 48-59, inner 60-67)
IBUG68_LIPS = tuple(range(48, 68))
_TIME = ("time", "timestamp", "t", "seconds", "time_s")
_FRAME = ("frame", "frame_number", "frameno")
_POINT = ("point", "landmark", "marker", "name", "point_name")
_OPENFACE = re.compile(r"^([xyXYZ])_(\d+)$")
_NAMED = re.compile(r"^(.+)[_.]([xyzXYZ])$")


def _rows(path, delimiter):
    text = decode_text(read_bytes(path), path)
    lines = [(i, s) for i, s in enumerate(text.split("\n"), start=1) if s.strip() and not s.lstrip().startswith("#")]
    if not lines:
        raise ImportFormatError(path, "is empty; expected a header row and rows of landmark coordinates")
    if delimiter is None:
        head = lines[0][1]
        delimiter = max([",", ";", "\t"], key=head.count)
        if head.count(delimiter) == 0:
            delimiter = None if len(head.split()) > 1 else ","
    if delimiter is None:  # whitespace separated
        parsed = [(i, s.split()) for i, s in lines]
    else:
        try:
            parsed = list(zip([i for i, _ in lines], csv.reader([s for _, s in lines], delimiter=delimiter)))
        except csv.Error as exc:
            raise ImportFormatError(path, f"CSV syntax error: {exc}") from None
    header = [h.strip() for h in parsed[0][1]]
    return parsed[0][0], header, parsed[1:]


def _numbers(body, col, path, what):
    """Column ``col`` of the body rows as floats (empty / 'nan' -> NaN)."""
    out = np.empty(len(body), np.float64)
    for r, (line, row) in enumerate(body):
        s = row[col].strip()
        if s == "" or s.lower() in ("nan", "na", "null", "-nan"):
            out[r] = np.nan
            continue
        try:
            out[r] = float(s)
        except ValueError:
            raise ImportFormatError(path, f"{what} is {s[:30]!r}; expected a number", line=line) from None
    return out


def _find(header, names):
    low = [h.lower() for h in header]
    for n in names:
        if n in low:
            return low.index(n)
    return None


def _wide_points(header, space, path):
    """[(point name, [col x, col y(, col z)])] and dims for a wide header."""
    of = {}
    for j, h in enumerate(header):
        m = _OPENFACE.match(h)
        if m:
            axis = of.setdefault(m.group(1), {})
            if int(m.group(2)) in axis:
                raise _twice(path, header, axis[int(m.group(2))], j)
            axis[int(m.group(2))] = j
    if "x" in of and "y" in of or {"X", "Y", "Z"} <= set(of):
        three = {"X", "Y", "Z"} <= set(of) and set(of["X"]) == set(of["Y"]) == set(of["Z"])
        if space == "3d" and not three:
            raise ImportFormatError(path, "3-D landmarks were asked for but the header has no complete X_i, Y_i, "
                                    "Z_i columns")
        use3 = three and space != "2d"
        if not use3 and not ("x" in of and "y" in of and set(of["x"]) == set(of["y"])):
            raise ImportFormatError(path, "the x_i and y_i columns do not match; expected x_0..x_N and y_0..y_N")
        axes = ("X", "Y", "Z") if use3 else ("x", "y")
        idx = sorted(of[axes[0]])
        return [(str(i), [of[a][i] for a in axes]) for i in idx], (3 if use3 else 2), True
    named = {}
    order = []
    for j, h in enumerate(header):
        m = _NAMED.match(h)
        if m and h.lower() not in _TIME + _FRAME:
            nm = m.group(1)
            if nm not in named:
                order.append(nm)
            axes = named.setdefault(nm, {})
            if m.group(2).lower() in axes:
                raise _twice(path, header, axes[m.group(2).lower()], j)
            axes[m.group(2).lower()] = j
    for n in order:  # a point with one axis but not the other would be dropped without a word
        have = named[n]
        lack = [a for a in "xy" if a not in have]
        if lack and (len(lack) == 1 or "z" in have):
            got = ", ".join(repr(header[k]) for k in have.values())
            raise ImportFormatError(path, f"point {n!r} has column(s) {got} but no {n}_{lack[0]} column; expected "
                                    f"{n}_x and {n}_y (and {n}_z for 3-D) for every point")
    pts = [n for n in order if "x" in named[n] and "y" in named[n]]
    if not pts:
        raise ImportFormatError(path, f"header {header[:8]}...: no landmark columns; expected OpenFace x_0/y_0 "
                                "(X_0/Y_0/Z_0), <name>_x/<name>_y[/<name>_z] columns, or a long table with "
                                "frame, point, x, y[, z]", line=1)
    zs = [("z" in named[n]) for n in pts]
    if any(zs) and not all(zs):
        n = pts[zs.index(False)]
        raise ImportFormatError(path, f"point {n!r} has no z column while others do; expected every point "
                                "in 2-D or every point in 3-D")
    dims = 3 if all(zs) else 2
    return [(n, [named[n][a] for a in "xyz"[:dims]]) for n in pts], dims, False


def _twice(path, header, first: int, second: int) -> ImportFormatError:
    """The error for two header columns naming the same coordinate."""
    return ImportFormatError(path, f"columns {first + 1} ({header[first]!r}) and {second + 1} ({header[second]!r}) "
                             "name the same coordinate; expected each coordinate once")


@reports_repairs
def read_csv_landmarks(path, *, rate: float | None = None, points=None, space: str = "auto", face=None,
                       delimiter: str | None = None, alignment=None, tier: str | None = None,
                       fill_gaps: bool = True):
    """A CSV landmark track as one utterance.

    Parameters
    ----------
    path : str or Path
    rate : float, optional
        Frames per second; required when the file has no time column, otherwise it
        overrides the rate the times give.
    points : sequence of str/int, "lips" or None
        Landmarks to keep (names, or OpenFace indices); "lips" = :data:`IBUG68_LIPS`
        for OpenFace files. All by default.
    space : {"auto", "2d", "3d"}
        OpenFace files: the 3-D ``X_i Y_i Z_i`` columns when present ("auto"), or the
        2-D pixel ``x_i y_i`` ones.
    face : int, optional
        OpenFace ``face_id`` to keep when several faces were tracked (default: the first).
    delimiter : str, optional
        Field separator; sniffed from the header (``,`` ``;`` tab or blanks) by default.
    alignment, tier, fill_gaps : as the other readers.

    Returns
    -------
    Corpus
    """
    path = Path(path)
    if space not in ("auto", "2d", "3d"):
        raise ValueError(f"space={space!r}; expected 'auto', '2d' or '3d'")
    hline, header, body = _rows(path, delimiter)
    seen: dict[str, int] = {}
    for j, h in enumerate(header):
        if h and h in seen:
            raise _twice(path, header, seen[h], j)
        seen.setdefault(h, j)
    ncol = len(header)
    for line, row in body:
        if len(row) != ncol:
            raise ImportFormatError(path, f"{len(row)} fields; the header has {ncol}", line=line)
    if not body:
        raise ImportFormatError(path, "has a header but no data rows")
    ti, fi, pi = _find(header, _TIME), _find(header, _FRAME), _find(header, _POINT)
    lo = [h.lower() for h in header]
    if pi is not None and {"x", "y"} <= set(lo):
        return _read_long(path, header, body, ti, fi, pi, rate, points, alignment, tier, fill_gaps)
    fid = _find(header, ("face_id",))
    if fid is not None:
        ids = _numbers(body, fid, path, "face_id")
        want = face if face is not None else np.nanmin(ids) if np.isfinite(ids).any() else None
        if want is not None:
            others = sorted({float(i) for i in ids if i != want and np.isfinite(i)})
            body = [b for b, i in zip(body, ids) if i == want]
            if len(body) < 2:
                raise ImportFormatError(path, f"face_id {want:g} has {len(body)} rows; expected at least 2")
            if others:  # several faces were tracked: one is read, and the others are said to be left out
                from engine.io.repairs import report_repair

                report_repair(path, f"{len(ids) - len(body)} rows of other faces (face_id "
                              f"{', '.join(f'{i:g}' for i in others[:5])}) left out; face_id {want:g} is read")
    pts, dims, openface = _wide_points(header, space, path)
    if points is not None:
        if isinstance(points, str) and points == "lips":
            if not openface:
                raise ImportFormatError(path, "--points lips needs OpenFace's 68 numbered landmarks")
            points = IBUG68_LIPS
        names = [p for p, _ in pts]
        sel = []
        for p in points:
            key = str(p)
            if key not in names:
                raise ImportFormatError(path, f"has no landmark {p!r}; it has {names[:10]}...")
            sel.append(names.index(key))
        pts = [pts[k] for k in sel]
    cols = [c for _, cc in pts for c in cc]
    X = np.column_stack([_numbers(body, c, path, f"column {header[c]!r}") for c in cols])
    flags = np.zeros(X.shape, bool)
    si = _find(header, ("success",))
    if si is not None:
        flags |= (_numbers(body, si, path, "success") == 0)[:, None]
    if ti is not None:
        native = _column_rate(uniform_rate(_numbers(body, ti, path, f"time column {header[ti]!r}"), path),
                              rate, header[ti], path)
    elif rate is None:
        raise ImportFormatError(path, f"has no time column ({', '.join(_TIME)}); give the frame rate "
                                "(lipspace import --rate HZ)")
    else:
        native = plausible_rate(path, rate, "the frame rate given (--rate)")
    names = [("L" + n if openface else n) for n, _ in pts]
    frames = _fill_gaps(X, flags, path=path, names=[header[c] for c in cols], fill=fill_gaps, flagged="success 0",
                        nan="empty or NaN")
    phones, _ = resolve_alignment(path, alignment, tier=tier)
    return one_utterance_corpus(path, frames, native, dims=dims, phones=phones, point_names=names,
                                audio=sidecar_audio(path), units="mm" if openface and dims == 3 else "")


def _column_rate(native, rate, column, path) -> float:
    """The rate the time column gives; an explicit ``rate`` that disagrees is refused."""
    if rate is not None and abs(float(rate) - native) > 1e-3 * native:
        raise ImportFormatError(path, f"the time column {column!r} gives {native:g} Hz but a rate of "
                                f"{float(rate):g} Hz was given (--rate); leave the rate out to use the column's times, "
                                "or resample "
                                "('lipspace import --resample') to change it")
    return float(native)


#: at most this share of a long table's frame numbers may be missing (filled by interpolation)
MAX_MISSING_FRAMES = 0.5


def _frame_numbers(frame_keys, frame_of, keys, body, column, path):
    """Frame numbers as consecutive rows: integers, every missing number a gap to fill.

    Their samples are filled and reported as any dropout (:func:`engine.io._util.fill_gaps`);
    more than :data:`MAX_MISSING_FRAMES` of the span missing (e.g. a typo making frame
    1000000) is refused before allocating.
    """
    frac = np.flatnonzero(frame_keys != np.round(frame_keys))
    if frac.size:
        r = int(np.flatnonzero(keys == frame_keys[frac[0]])[0])
        raise ImportFormatError(path, f"frame number {frame_keys[frac[0]]:g} in column {column!r} is not a whole "
                                "number; expected frame numbers 0, 1, 2, ... (or a time column in seconds)",
                                line=body[r][0])
    span = int(frame_keys[-1] - frame_keys[0]) + 1
    if span == len(frame_keys):
        return frame_keys, frame_of
    n_missing = span - len(frame_keys)
    first = []  # the first ten missing numbers, without listing a typo's billion
    for k in np.flatnonzero(np.diff(frame_keys) > 1):
        first += [f"{m:g}" for m in np.arange(frame_keys[k] + 1, min(frame_keys[k + 1], frame_keys[k] + 11))]
        if len(first) >= 10:
            break
    shown = ", ".join(first[:10]) + (", ..." if n_missing > 10 else "")
    if n_missing > MAX_MISSING_FRAMES * span:
        raise ImportFormatError(path, f"column {column!r} numbers frames {frame_keys[0]:g} to {frame_keys[-1]:g} "
                                f"but {n_missing} of those {span} frames have no rows ({shown}); expected "
                                "consecutive frame numbers")
    return np.arange(frame_keys[0], frame_keys[-1] + 1, dtype=np.float64), \
        (frame_keys[frame_of] - frame_keys[0]).astype(np.intp)


def _read_long(path, header, body, ti, fi, pi, rate, points, alignment, tier, fill_gaps):
    lo = [h.lower() for h in header]
    axes = [lo.index(a) for a in ("x", "y", "z") if a in lo]
    dims = len(axes)
    key_col = fi if fi is not None else ti
    if key_col is None:
        raise ImportFormatError(path, "a long landmark table needs a 'frame' or 'time' column", line=1)
    keys = _numbers(body, key_col, path, f"column {header[key_col]!r}")
    if not np.isfinite(keys).all():
        r = int(np.flatnonzero(~np.isfinite(keys))[0])
        raise ImportFormatError(path, f"{header[key_col]!r} is empty or not a number", line=body[r][0])
    names = [row[pi].strip() for _, row in body]
    frame_keys, frame_of = np.unique(keys, return_inverse=True)
    if key_col == fi:  # frame numbers: missing numbers are dropped frames, never closed up
        frame_keys, frame_of = _frame_numbers(frame_keys, frame_of, keys, body, header[fi], path)
    point_order = list(dict.fromkeys(names))
    if points is not None:
        want = [str(p) for p in points]
        bad = [p for p in want if p not in point_order]
        if bad:
            raise ImportFormatError(path, f"has no point(s) {bad}; it has {point_order[:10]}")
        point_order = want
    col_of = {n: k for k, n in enumerate(point_order)}
    X = np.full((len(frame_keys), len(point_order) * dims), np.nan)
    seen = np.zeros((len(frame_keys), len(point_order)), bool)
    vals = np.column_stack([_numbers(body, a, path, f"column {header[a]!r}") for a in axes])
    for r, ((line, _), nm) in enumerate(zip(body, names)):
        k = col_of.get(nm)
        if k is None:
            continue
        f = frame_of[r]
        if seen[f, k]:
            raise ImportFormatError(path, f"point {nm!r} appears twice in frame {frame_keys[f]:g}", line=line)
        seen[f, k] = True
        X[f, k * dims:(k + 1) * dims] = vals[r]
    if ti is not None:
        t = _numbers(body, ti, path, f"time column {header[ti]!r}")
        first = np.zeros(len(frame_keys))
        first[frame_of[::-1]] = t[::-1]  # each frame's time from its first row
        native = _column_rate(uniform_rate(first, path), rate, header[ti], path)
    elif rate is None:
        raise ImportFormatError(path, "has frame numbers but no time column; give the frame rate (lipspace import "
                                "--rate HZ)")
    else:
        native = plausible_rate(path, rate, "the frame rate given (--rate)")
    frames = _fill_gaps(X, np.repeat(~seen, dims, axis=1), path=path,
                        names=[f"{n}_{a}" for n in point_order for a in "xyz"[:dims]], fill=fill_gaps,
                        flagged="without a row in the table", nan="empty or NaN", first_frame=int(frame_keys[0]))
    phones, _ = resolve_alignment(path, alignment, tier=tier)
    return one_utterance_corpus(path, frames, native, dims=dims, phones=phones, point_names=point_order,
                                audio=sidecar_audio(path), units="")
