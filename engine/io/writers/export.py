"""Exporters: trajectories (CSV, NPY), mesh sequences (OBJ, PLY), tables (CSV).

Every file is written atomically (temporary file beside it, then renamed), so a crash
or an error never leaves a half-written file and an existing file stays intact.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from engine.files.atomic import atomic_write
from engine.io.writers.meshfile import write_obj, write_ply

__all__ = ["write_trajectory_csv", "write_trajectory_npy", "write_mesh_sequence", "write_table_csv",
           "point_columns", "corpus_columns"]


def point_columns(point_names, dims: int) -> list[str]:
    """Column names ``<point>_x``, ``<point>_y`` [, ``<point>_z``] per point (what the CSV reader pairs)."""
    return [f"{n}_{a}" for n in point_names for a in "xyz"[:dims]]


def corpus_columns(corpus) -> list[str]:
    """Frame column names of a corpus: its point names (or ``p0, p1, ...``) with axes."""
    names = corpus.point_names or [f"p{k}" for k in range(corpus.n_points)]
    return point_columns(names, corpus.dims)


def write_trajectory_csv(path, values, *, rate: float | None = None, times=None, columns=None,
                         precision: int = 7) -> Path:
    """A trajectory as CSV: a header row ``time,<columns...>``, then one row per frame.

    Parameters
    ----------
    path : str or Path
    values : array of shape (n_frames, n_columns)
        E.g. F^y (manifold coordinates), F^x (shape components) or frames.
    rate : float, optional
        Frame rate; times are ``k / rate``. One of ``rate`` / ``times`` is required.
    times : array of shape (n_frames,), optional
        Frame times in seconds.
    columns : sequence of str, optional
        Column names (default ``c0, c1, ...``); for frames use :func:`corpus_columns`.
    precision : int
        Significant digits.

    Returns
    -------
    Path
    """
    V = np.asarray(values, dtype=np.float64)
    if V.ndim == 1:
        V = V[:, None]
    if V.ndim != 2:
        raise ValueError(f"values must be (n_frames, n_columns), got shape {V.shape}")
    n, c = V.shape
    if times is None:
        if rate is None or not rate > 0:
            raise ValueError(f"give rate (Hz, > 0) or times for the time column; got rate={rate!r}")
        t = np.arange(n) / float(rate)
    else:
        t = np.asarray(times, dtype=np.float64).ravel()
        if t.shape[0] != n:
            raise ValueError(f"times has {t.shape[0]} entries for {n} frames")
    cols = [f"c{k}" for k in range(c)] if columns is None else [str(x) for x in columns]
    if len(cols) != c:
        raise ValueError(f"{len(cols)} column names for {c} columns")
    if "time" in cols:
        raise ValueError("'time' is the name of the first column; choose other column names")
    with atomic_write(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(["time", *cols])
            buf = io.StringIO()
            np.savetxt(buf, np.column_stack([t, V]), fmt=f"%.{precision}g", delimiter=",")
            fh.write(buf.getvalue())
    return Path(path)


def write_trajectory_npy(path, values, *, dtype=np.float32) -> Path:
    """A trajectory (any array, typically (n_frames, k)) as ``.npy`` (float32 by default)."""
    arr = np.asarray(values, dtype=dtype)
    with atomic_write(path) as tmp:
        with open(tmp, "wb") as fh:
            np.save(fh, arr, allow_pickle=False)
    return Path(path)


def write_mesh_sequence(directory, frames, *, faces=None, dims: int = 3, format: str = "obj",
                        binary: bool = False, prefix: str = "frame", clear: bool = False,
                        labels=None, progress=None) -> list[Path]:
    """One mesh file per frame: ``<directory>/<prefix>_00000.obj`` ... (or ``.ply``).

    Parameters
    ----------
    directory : str or Path
        Created if missing.
    frames : array of shape (n_frames, dims * V) or (n_frames, V, 3)
        Points per frame (2-D points get z = 0).
    faces : array of shape (F, 3), optional
        Triangles; without them the files hold points only.
    dims : {2, 3}
        Coordinates per point in flat ``frames``.
    format : {"obj", "ply"}
    binary : bool
        Binary little-endian PLY (ignored for OBJ).
    prefix : str
        File name prefix.
    clear : bool
        Remove older ``<prefix>_*.<format>`` files in the directory that this export does
        not overwrite (after writing); without it such files are an error (they would be
        read back as extra frames).
    labels : sequence of (str, int), optional
        Named vertices (e.g. the sensors of a lip contour mesh, from
        :func:`engine.recordings.lipcontour.mesh_geometry`), written into every file as
        :mod:`engine.io.readers.meshfile` describes (OBJ comments and groups, PLY header comments).
    progress : callable, optional
        ``progress("export", done, total)``.

    Returns
    -------
    list of Path
        The files written, in frame order (each written atomically). The names sort in
        frame order and the directory reads back with :func:`engine.io.read_mesh_sequence`.
    """
    from engine.recordings.corpus import frame_points

    fmt = format.lower()
    if fmt not in ("obj", "ply"):
        raise ValueError(f"format={format!r}; expected 'obj' or 'ply'")
    A = np.asarray(frames)
    pts = A if A.ndim == 3 else frame_points(A, dims)
    if pts.ndim != 3 or pts.shape[2] != 3:
        raise ValueError(f"frames must be (n, dims*V) or (n, V, 3), got {A.shape}")
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    width = max(5, len(str(len(pts) - 1)))
    names = {f"{prefix}_{k:0{width}d}.{fmt}" for k in range(len(pts))}
    stale = [q for q in d.glob(f"{prefix}_*.{fmt}") if q.name not in names]
    if stale and not clear:
        raise ValueError(f"{d} already holds {len(stale)} other '{prefix}_*.{fmt}' frame file(s), e.g. "
                         f"{stale[0].name}; they would be read back as extra frames. Choose an empty directory or "
                         "pass clear=True")
    out = []
    for k, P in enumerate(pts):
        p = d / f"{prefix}_{k:0{width}d}.{fmt}"
        if fmt == "obj":
            write_obj(p, P, faces, labels=labels)
        else:
            write_ply(p, P, faces, binary=binary, labels=labels)
        out.append(p)
        if progress is not None:
            progress("export", k + 1, len(pts))
    for q in stale:
        q.unlink()
    return out


def write_table_csv(path, table, *, columns=None, precision: int = 6) -> Path:
    """A table (e.g. phone-cluster statistics) as CSV with a header row.

    Parameters
    ----------
    path : str or Path
    table : list of dict, or dict of column name -> sequence
        Rows as dicts (columns in first-seen order; missing cells are empty), or columns
        of equal length.
    columns : sequence of str, optional
        Column order (and selection).
    precision : int
        Significant digits for floats.

    Returns
    -------
    Path
    """
    if isinstance(table, dict):
        names = list(table)
        lens = {len(table[k]) for k in names}
        if len(lens) > 1:
            raise ValueError(f"columns have different lengths {sorted(lens)}; expected equal lengths")
        n = lens.pop() if lens else 0
        rows = [{k: table[k][i] for k in names} for i in range(n)]
    else:
        rows = [dict(r) for r in table]
        names = list(dict.fromkeys(k for r in rows for k in r))
    if columns is not None:
        names = [str(c) for c in columns]

    def cell(v):
        if v is None:
            return ""
        if isinstance(v, (float, np.floating)):
            return "inf" if np.isposinf(v) else "-inf" if np.isneginf(v) else "" if np.isnan(v) else \
                f"{float(v):.{precision}g}"
        if isinstance(v, (np.integer,)):
            return str(int(v))
        if isinstance(v, (list, tuple, np.ndarray)):
            return " ".join(cell(x) for x in np.ravel(v))
        return str(v)

    with atomic_write(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(names)
            for r in rows:
                w.writerow([cell(r.get(k)) for k in names])
    return Path(path)
