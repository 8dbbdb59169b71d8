"""Which entries of a folder Lipspace shares with the user (the cache) it wrote itself.

The cache folder can be one the user named (``$LIPSPACE_CACHE_DIR``), holding files of
their own; a name that looks like a cache entry proves nothing. Whatever writes a cache
entry calls :func:`mark` once it is complete: a small marker in ``<root>/.lipspace-entries/``
records the entry's device, inode and (for a file) size and modification time.
:func:`owned` is true only while the entry is that very file or folder, so a user's file
put at the same name later (or copied over it) is not Lipspace's, and pruning or
``lipspace cache --clear`` leave it alone (:mod:`app.files.cache`).
"""
from __future__ import annotations

import contextlib
import json
import os
import stat
from pathlib import Path
from urllib.parse import quote

__all__ = ["MARKS", "mark", "owned", "unmark"]

#: the folder of markers, in the cache's root
MARKS = ".lipspace-entries"


def _marker(path: Path, root: Path) -> Path | None:
    try:
        rel = Path(os.path.abspath(path)).relative_to(os.path.abspath(root))
    except ValueError:
        return None
    return Path(root) / MARKS / (quote(rel.as_posix(), safe="") + ".json")


def _identity(path: Path) -> dict | None:
    try:
        st = os.lstat(path)
    except OSError:
        return None
    if stat.S_ISLNK(st.st_mode):
        return None  # a link is never an entry Lipspace wrote
    d = {"dev": st.st_dev, "ino": st.st_ino, "dir": stat.S_ISDIR(st.st_mode)}
    if not d["dir"]:  # a folder gains files (audio is written into it later); a file never changes
        d.update(size=st.st_size, mtime_ns=st.st_mtime_ns)
    return d


def mark(path, root) -> bool:
    """Record that Lipspace wrote ``path`` (a file or folder inside the folder ``root``); False when it
    could not (a read-only cache: the entry is then simply never pruned)."""
    who = _identity(Path(path))
    m = _marker(Path(path), Path(root))
    if who is None or m is None:
        return False
    try:
        m.parent.mkdir(parents=True, exist_ok=True)
        tmp = m.with_name(f".{m.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(who), encoding="utf-8")
        os.replace(tmp, m)
    except OSError:
        return False
    return True


def owned(path, root) -> bool:
    """Whether ``path`` is still the very entry Lipspace wrote and marked under ``root``."""
    m = _marker(Path(path), Path(root))
    if m is None:
        return False
    from engine.files.bounded import read_bounded

    try:
        recorded = json.loads(read_bounded(m, limit=4096, what="cache marker"))
    except (OSError, ValueError):
        return False
    return isinstance(recorded, dict) and recorded == _identity(Path(path))


def unmark(path, root) -> None:
    """Forget the marker of ``path`` (after it was deleted)."""
    m = _marker(Path(path), Path(root))
    if m is not None:
        with contextlib.suppress(OSError):
            m.unlink()
