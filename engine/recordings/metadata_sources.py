"""Where per-utterance metadata comes from: a file-name pattern with named groups, a metadata table.

``lipspace import --fields-from 're:PATTERN'`` reads fields from each input's file name
(its stem, without the extension): every named group of the regular expression is a
field, e.g. ``re:^(?P<speaker>[A-Z]+?)(?P<sex>[FM])(?P<emotion>[A-Z]{2})(?P<text>[0-9]+)$``
gives ``XYZFIA01`` speaker ``XYZ``, sex ``F``, emotion ``IA``, text ``01``.

``lipspace import --metadata meta.csv`` reads a table as labs keep them: one header row,
comma-, semicolon- or tab-separated (the most frequent of the three in the header), UTF-8;
one row per recording, keyed by the file name (with or without its extension, or its
path relative to the folder imported) in the column named ``file``, ``filename``,
``recording``, ``utterance``, ``name`` or ``id`` (else the first column; ``--metadata-key``
names another). Every other column is a field, its header turned into snake_case
(``Speaker ID`` -> ``speaker_id``); empty cells and ``NA`` are missing.

Both may be given; a field they both set must agree for every file. A pattern that
matches no file name is an error, as is one that misses some of them (naming them); a
table row for a file not imported and a file without a row are reported (a warning
naming them: the import goes on, the files without a row have those fields missing).
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from engine.recordings.metadata import MetadataError, check_field_name

__all__ = ["FieldPattern", "MetadataTable", "read_metadata_table", "assign_fields", "snake_case", "KEY_COLUMNS",
           "MISSING_VALUES"]

#: header names taken as the key column (compared in snake_case)
KEY_COLUMNS = ("file", "filename", "file_name", "recording", "utterance", "name", "id", "stem")
#: cells read as missing
MISSING_VALUES = frozenset({"", "na", "n/a", "nan", "null", "none", "-"})


def snake_case(header: str) -> str:
    """``"Speaker ID"`` -> ``"speaker_id"``: lower case, runs of other characters as one ``_``."""
    s = re.sub(r"[^0-9a-z]+", "_", str(header).strip().lower()).strip("_")
    return s


class FieldPattern:
    """Fields of a file from its name: the named groups of a regular expression searched in the stem.

    Parameters
    ----------
    spec : str
        ``"re:PATTERN"`` (the ``re:`` may be left out) with at least one named group
        ``(?P<name>...)``; group names become field names (lower case).

    Raises
    ------
    MetadataError
        A pattern that does not compile, has no named group or names a field the tables
        already have as a column.
    """

    def __init__(self, spec: str):
        self.spec = str(spec)
        text = self.spec[3:] if self.spec.startswith("re:") else self.spec
        try:
            self.pattern = re.compile(text)
        except re.error as exc:
            raise MetadataError(f"--fields-from {self.spec!r}: not a regular expression ({exc})") from None
        if not self.pattern.groupindex:
            raise MetadataError(f"--fields-from {self.spec!r} has no named group; name each part of the file "
                                "name, e.g. 're:^(?P<speaker>[A-Z]+?)(?P<sex>[FM])(?P<emotion>[A-Z]{2})"
                                "(?P<text>[0-9]+)$'")
        self.names = {g: check_field_name(g.lower(), where=f"--fields-from group (?P<{g}>...)")
                      for g in self.pattern.groupindex}

    def __repr__(self):
        return f"FieldPattern({self.spec!r})"

    def match(self, path) -> dict[str, str] | None:
        """``{field: value}`` for ``path`` (an unmatched optional group gives ""), or None if the stem does not
        match."""
        m = self.pattern.search(Path(str(path)).stem)
        if m is None:
            return None
        return {self.names[g]: (m.group(g) or "") for g in self.pattern.groupindex}

    def fields(self, paths) -> dict[str, dict[str, str]]:
        """``{str(path): fields}`` of every path; MetadataError naming the files it does not match."""
        out, missed = {}, []
        for p in paths:
            f = self.match(p)
            if f is None:
                missed.append(Path(str(p)).stem)
            else:
                out[str(p)] = f
        if missed:
            shown = ", ".join(missed[:5]) + (" ..." if len(missed) > 5 else "")
            what = ("matches none of the" if len(missed) == len(list(paths)) else
                    f"does not match {len(missed)} of the")
            raise MetadataError(f"--fields-from {self.spec!r} {what} {len(out) + len(missed)} file names "
                                f"(stems, without the extension): {shown}; give a pattern that fits every "
                                "name (nothing was read)")
        return out


class MetadataTable:
    """A lab's metadata table: one row per recording, keyed by file name.

    Attributes
    ----------
    path : Path
    key : str
        The header of the key column, as written.
    fields : list of str
        Field names (snake_case headers of the other columns), in column order.
    rows : dict of str to dict
        ``{key value: {field: value}}``; missing cells are "".
    lines : dict of str to int
        The line of each key value, for messages.
    """

    def __init__(self, path, key, fields, rows, lines):
        self.path, self.key, self.fields, self.rows, self.lines = Path(path), key, fields, rows, lines

    def __repr__(self):
        return f"MetadataTable({str(self.path)!r}, key={self.key!r}, {len(self.rows)} rows, fields={self.fields})"

    def lookup(self, path, root=None) -> str | None:
        """The key value naming ``path``: its name, its stem, its path relative to ``root``, case-insensitively
        as a last resort; None if no row names it."""
        p = Path(str(path))
        cands = [p.name, p.stem]
        if root is not None:
            try:
                rel = p.relative_to(root)
                cands += [rel.as_posix(), rel.with_suffix("").as_posix()]
            except ValueError:
                pass
        for c in cands:
            if c in self.rows:
                return c
        low = {k.lower(): k for k in self.rows}
        return next((low[c.lower()] for c in cands if c.lower() in low), None)


def read_metadata_table(path, *, key: str | None = None) -> MetadataTable:
    """Read a metadata table (format in the module docstring).

    Raises
    ------
    MetadataError
        Naming the file and line: no header, a row of the wrong length, a key repeated or
        empty, a header that cannot be a field name, two headers giving one field, no
        column ``key``.
    FileNotFoundError
    """
    import csv

    path = Path(path)
    text = _read_text(path)

    lines = text.splitlines()
    first = next((i for i, ln in enumerate(lines) if ln.strip()), None)
    if first is None:
        raise MetadataError(f"{path}: the metadata table is empty; expected a header row and one row per file")
    sep = max(",;\t", key=lambda c: lines[first].count(c))
    if lines[first].count(sep) == 0:
        raise MetadataError(f"{path}, line {first + 1}: the header {lines[first][:60]!r} has one column; expected "
                            "the file-name column and at least one field, separated by ',', ';' or tabs")
    rows = list(csv.reader(lines[first:], delimiter=sep))
    header = [h.strip() for h in rows[0]]
    snake = [snake_case(h) for h in header]
    if key is not None:
        if key not in header and snake_case(key) not in snake:
            raise MetadataError(f"{path}: no column {key!r} (--metadata-key); the columns are {header}")
        k = header.index(key) if key in header else snake.index(snake_case(key))
    else:
        k = next((i for i, s in enumerate(snake) if s in KEY_COLUMNS), 0)
    fields: list[str]
    cols: list[int]
    fields, cols = [], []
    for i, (h, s) in enumerate(zip(header, snake)):
        if i == k or (not h and all(i >= len(r) or not r[i].strip() for r in rows[1:])):
            continue  # the key, and an unnamed empty column (a trailing separator)
        name = check_field_name(s, where=f"{path}, line {first + 1}, column {i + 1} ({h!r})")
        if name in fields:
            raise MetadataError(f"{path}, line {first + 1}: columns {header[cols[fields.index(name)]]!r} and {h!r} "
                                f"both give the field {name!r}; rename one")
        fields.append(name)
        cols.append(i)
    if not fields:
        raise MetadataError(f"{path}: no field columns besides the key column {header[k]!r}")
    where: dict[str, Any]
    out, where = {}, {}
    for r, row in enumerate(rows[1:], start=first + 2):
        if not any(c.strip() for c in row):
            continue
        if len(row) > len(header) and any(c.strip() for c in row[len(header):]):
            raise MetadataError(f"{path}, line {r}: {len(row)} cells but the header has {len(header)} columns")
        name = row[k].strip() if k < len(row) else ""
        if not name:
            raise MetadataError(f"{path}, line {r}: the file-name column {header[k]!r} is empty")
        if name in out:
            raise MetadataError(f"{path}, line {r}: file {name!r} has a row already (line {where[name]}); expected "
                                "one row per file")
        vals = {}
        for f, i in zip(fields, cols):
            v = row[i].strip() if i < len(row) else ""
            vals[f] = "" if v.lower() in MISSING_VALUES else v
        out[name], where[name] = vals, r
    if not out:
        raise MetadataError(f"{path}: the metadata table has a header but no rows")
    return MetadataTable(path, header[k], fields, out, where)


def _read_text(path: Path) -> str:
    """The table's text: UTF-8 (with or without BOM) or UTF-16 with a BOM; MetadataError naming the line of a
    byte that is neither."""
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such metadata table")
    if not path.is_file():
        raise MetadataError(f"{path}: is not a file; --metadata takes a table (CSV) of one row per recording")
    data = path.read_bytes()
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        try:
            return data.decode("utf-16")
        except UnicodeDecodeError as exc:
            raise MetadataError(f"{path}: not valid UTF-16 text at byte {exc.start}") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise MetadataError(f"{path}, line {line}: byte 0x{data[exc.start]:02x} is not UTF-8; save the table as "
                            "UTF-8 CSV (spreadsheet programs offer it as 'CSV UTF-8')") from None


def assign_fields(paths, *, pattern=None, table=None, root=None) -> tuple[dict, list[str]]:
    """The fields of every input from a pattern and / or a table.

    Parameters
    ----------
    paths : sequence of str or Path
        The input files.
    pattern : FieldPattern or str, optional
    table : MetadataTable or str or Path, optional
    root : Path, optional
        The folder the inputs were found in (a table may name them relative to it).

    Returns
    -------
    fields : dict of str to dict
        ``{str(path): {field: value}}`` for every path (possibly empty dicts).
    notes : list of str
        Warnings to show: table rows no input matches, inputs no row names (their table
        fields are missing).

    Raises
    ------
    MetadataError
        The pattern misses a file; no input is named by the table; the pattern and the
        table disagree on a field of a file (naming the file, the field and both values).
    """
    paths = [str(p) for p in paths]
    out: dict[str, dict[str, str]] = {p: {} for p in paths}
    notes = []
    if pattern is not None:
        pat = pattern if isinstance(pattern, FieldPattern) else FieldPattern(pattern)
        for p, f in pat.fields(paths).items():
            out[p].update(f)
    if table is not None:
        tab = table if isinstance(table, MetadataTable) else read_metadata_table(table)
        used, missing = set(), []
        for p in paths:
            k = tab.lookup(p, root)
            if k is None:
                missing.append(p)
                continue
            used.add(k)
            for name, v in tab.rows[k].items():
                old = out[p].get(name, "")
                if old and v and old != v:
                    raise MetadataError(f"{p}: field {name!r} is {old!r} by --fields-from but {v!r} in {tab.path} "
                                        f"(line {tab.lines[k]}); make them agree, or leave the field out of one")
                out[p][name] = v or old
        if not used:
            shown = ", ".join(list(tab.rows)[:3])
            raise MetadataError(f"{tab.path}: no row names any of the {len(paths)} inputs (column {tab.key!r} holds "
                                f"e.g. {shown}; the inputs are e.g. {Path(paths[0]).name}); key the rows by file "
                                "name, or name the key column with --metadata-key")
        if missing:
            names = ", ".join(Path(p).name for p in missing[:5]) + (" ..." if len(missing) > 5 else "")
            notes.append(f"{tab.path}: no row for {len(missing)} of {len(paths)} inputs ({names}); their fields "
                         f"{', '.join(tab.fields)} are missing (NA)")
        extra = [k for k in tab.rows if k not in used]
        if extra:
            names = ", ".join(extra[:5]) + (" ..." if len(extra) > 5 else "")
            one = len(extra) == 1
            notes.append(f"{tab.path}: {len(extra)} row{'' if one else 's'} name{'s' if one else ''} no input "
                         f"({names}; line{'' if one else 's'} {', '.join(str(tab.lines[k]) for k in extra[:5])}); "
                         f"{'it was' if one else 'they were'} not used")
    return out, notes
