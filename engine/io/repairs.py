"""Repairs made while a file is read, reported per file in the corpus history.

A reader that repairs its input (interpolates dropouts, renames clashing markers, cuts an
alignment at the end of the data, silences non-finite audio samples) says so through
:func:`report_repair`: one line naming the file, which frames or samples, how many and
how they were repaired. Nothing is repaired without such a line.

Where the line goes:

* every reader in :mod:`engine.io` is wrapped by :func:`reports_repairs`: the lines of
  one read are appended to the returned corpus's ``history`` (kept in the corpus file,
  printed by ``lipspace import`` and listed by ``lipspace info``);
* any caller can collect them too with :func:`collecting_repairs` (the window and the
  commands that open a recording directly show them as warnings);
* with no collector active (a library call outside the readers) the line is issued as an
  :class:`engine.io.errors.ImportDataWarning`.

Collectors nest: a line reaches every active collector, innermost first.
"""
from __future__ import annotations

import contextlib
import contextvars
import functools
import warnings

import numpy as np

__all__ = ["report_repair", "collecting_repairs", "reports_repairs", "frame_runs"]

_COLLECTORS: contextvars.ContextVar[tuple] = contextvars.ContextVar("lipspace_repair_collectors", default=())


def report_repair(path, message: str) -> str:
    """Report one repair of the file ``path``; returns the line (``"<path>: <message>"``)."""
    line = f"{path}: {message}" if path is not None else str(message)
    active = _COLLECTORS.get()
    if not active:
        from engine.io.errors import ImportDataWarning

        warnings.warn(ImportDataWarning(line), stacklevel=2)
        return line
    for notes in active:
        if line not in notes:
            notes.append(line)
    return line


@contextlib.contextmanager
def collecting_repairs():
    """Collect the repair lines reported inside the block; yields the list they are appended to."""
    notes: list[str] = []
    token = _COLLECTORS.set(_COLLECTORS.get() + (notes,))
    try:
        yield notes
    finally:
        _COLLECTORS.reset(token)


def reports_repairs(reader):
    """Decorate a reader returning a :class:`engine.recordings.corpus.Corpus`: the repairs it reported
    are appended to the corpus's ``history`` (once each)."""

    @functools.wraps(reader)
    def read(*args, **kwargs):
        with collecting_repairs() as notes:
            corpus = reader(*args, **kwargs)
        corpus.history.extend(n for n in notes if n not in corpus.history)
        return corpus

    return read


def frame_runs(rows, *, limit: int = 6, word: str = "frame") -> str:
    """``"frames 7, 8, 20-31 and 3 more runs"``: the indices ``rows`` (sorted or not) as runs."""
    idx = np.unique(np.asarray(rows, dtype=np.int64))
    if idx.size == 0:
        return f"no {word}s"
    cut = np.flatnonzero(np.diff(idx) > 1) + 1
    starts = np.split(idx, cut)
    parts = []
    for run in starts[:limit]:
        a, b = int(run[0]), int(run[-1])
        parts.append(f"{a}" if a == b else f"{a}, {b}" if b == a + 1 else f"{a}-{b}")
    more = len(starts) - limit
    tail = f" and {more} more run{'s' * (more != 1)}" if more > 0 else ""
    return f"{word}{'s' * (idx.size != 1)} {', '.join(parts)}{tail}"
