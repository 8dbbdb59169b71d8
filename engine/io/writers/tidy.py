"""Tidy tables out: a :class:`engine.manifold.frame_table.FrameTable` as CSV or Parquet, its units in a JSON sidecar.

The CSV is what ``read.csv``, ``readr::read_csv`` and ``pandas.read_csv`` read without
options: one header row of snake_case names, comma-separated, UTF-8, text quoted only
where needed, ``NA`` for a missing value, numbers to 7 significant digits. Units and
column meanings go to ``<table>.json`` beside it (a header comment would need
``comment=`` in every reader). Parquet (needs pyarrow, the ``parquet`` extra) holds the
same columns with their types, and the same metadata in its schema. Table and sidecar
are written atomically.
"""
from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np

from engine.files.atomic import atomic_write

__all__ = ["write_frame_table", "sidecar_path", "TABLE_SUFFIXES", "have_parquet", "NA"]

#: how a missing value is written (R's read.csv / readr and pandas read it as missing without options)
NA = "NA"

#: file endings :func:`write_frame_table` writes
TABLE_SUFFIXES = (".csv", ".parquet")


def have_parquet() -> bool:
    """Whether pyarrow is installed (Parquet output)."""
    import importlib.util

    return importlib.util.find_spec("pyarrow") is not None


def sidecar_path(path) -> Path:
    """Where the units of table ``path`` go: ``frames.csv`` -> ``frames.csv.json``."""
    p = Path(path)
    return p.with_name(p.name + ".json")


def _csv_text(x, na: str) -> str:
    """One text cell as the csv module writes it (quoted only when it holds a comma, quote or line break)."""
    if x is None:
        return na
    x = str(x)
    if any(ch in x for ch in ',"\n\r'):
        return '"' + x.replace('"', '""') + '"'
    return x


def _csv_rows(columns, na: str):
    """``(row format, column lists)``: one ``%`` format per row is the fast way to write many numbers."""
    fmts, lists = [], []
    for v in columns:
        v = np.asarray(v)
        if v.dtype.kind == "f" and np.isfinite(v).all():
            fmts.append("%.7g")
            lists.append(v.astype(np.float64).tolist())
        elif v.dtype.kind in "iub":
            fmts.append("%d")
            lists.append(v.astype(np.int64).tolist())
        elif v.dtype.kind == "f":  # non-finite values: missing
            fmts.append("%s")
            lists.append([f"{x:.7g}" if np.isfinite(x) else na for x in v.tolist()])
        else:
            fmts.append("%s")
            lists.append([_csv_text(x, na) for x in v.tolist()])
    return ",".join(fmts) + "\n", lists


def write_frame_table(path, table, *, sidecar=None, name=None) -> list[Path]:
    """Write ``table`` to ``path`` (``.csv`` or ``.parquet``) and its sidecar JSON; returns both paths.

    ``sidecar``: where the JSON goes (default :func:`sidecar_path` of ``path``); ``name``: the
    table's file name the JSON states (default ``path``'s), for writing to staged paths.
    """

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in TABLE_SUFFIXES:
        raise ValueError(f"{path}: a frame table ends in {' or '.join(TABLE_SUFFIXES)}")
    meta = table.metadata(name or path.name)
    side = sidecar_path(path) if sidecar is None else Path(sidecar)
    with atomic_write(path) as tmp, atomic_write(side) as tmp_side:
        if suffix == ".csv":
            fmt, cols = _csv_rows(table.columns.values(), NA)
            with open(tmp, "w", encoding="utf-8", newline="") as fh:
                fh.write(",".join(_csv_text(n, NA) for n in table.columns) + "\n")
                rows = zip(*cols)
                while chunk := list(itertools.islice(rows, 8192)):
                    fh.write("".join(fmt % r for r in chunk))
        else:
            _write_parquet(tmp, table, meta)
        tmp_side.write_text(json.dumps(meta, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    return [path, side]


def _write_parquet(tmp, table, meta):
    if not have_parquet():
        raise ImportError("writing Parquet needs pyarrow: pip install 'lipspace[parquet]' (or write .csv)")
    import pyarrow as pa
    import pyarrow.parquet as pq

    arrays = {}
    for name, v in table.columns.items():
        v = np.asarray(v)
        if v.dtype == object:
            arrays[name] = pa.array(list(v), type=pa.string())
        else:
            arrays[name] = pa.array(v)
    t = pa.table(arrays)
    t = t.replace_schema_metadata({b"lipspace": json.dumps(meta, ensure_ascii=False).encode("utf-8")})
    pq.write_table(t, str(tmp))
