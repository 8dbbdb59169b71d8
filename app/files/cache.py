"""Lipspace's cache folder: what is in it, how big it is, pruning old entries, clearing it (Qt-free).

The cache holds the synthetic talker's generated corpora (``synthetic-<preset>-<key>.npz``,
with their speech audio in ``synthetic-<preset>-<key>-audio/``), the manifolds
fitted to them (``manifolds/synthetic-<preset>-...npz``), each corpus's measured
choice of synthesis method (``method-choice/<data key>-<code key>.json``,
:mod:`engine.synthesis.method_choice`), the densities of the point clouds the explorer drew
(``density/<key>.npy``, :mod:`app.files.density_cache`) and the explorer's sound (``sound/recording-<key>/``,
a recording's extracted audio; ``sound/speech-<key>.wav``, synthesised text spoken:
:mod:`app.files.sound`). Every entry's name carries a
key made from the code and parameters that produced it (generator, fitting
algorithms, file format), so an entry made by other code is never used; it is only
left behind. :func:`prune` deletes those left-behind entries of a preset once a
current one has been written, so the folder holds one corpus and one manifold per
preset instead of one per code version (they are 50-200 MB each).

Only what Lipspace wrote is ever deleted: an entry counts when its writer marked it
(:mod:`engine.files.ownership`: the marker records the very file or folder, so a user's
file that merely has such a name, or was copied over one, is left alone), and the atomic
writer's temporary files count when their name is that writer's and the process named in
it has ended. The folder may be one the user named with ``$LIPSPACE_CACHE_DIR``;
:func:`entries` lists the look-alikes it leaves alone as ``owned=False``.
"""
from __future__ import annotations

import re
import shutil
from dataclasses import dataclass
from pathlib import Path

from engine.files.ownership import MARKS

__all__ = ["CACHE_DIR_ENV", "CacheEntry", "cache_dir", "entries", "total_bytes", "newest", "prune", "clear"]

#: a cached corpus or manifold file, or a corpus's audio folder, or the atomic writer's temporary file of one
_ENTRY = re.compile(r"^(?:synthetic-(?P<preset>[A-Za-z0-9_]+)-.+?(?:\.npz|-audio)|"
                    r"\.synthetic-.+\.p(?P<pid>\d+)-[a-z0-9_]{8}\.part\.npz)$")
#: a corpus's measured choice of synthesis method (engine.synthesis.method_choice.choice_path)
_CHOICE = re.compile(r"^[0-9a-f]{16}-[0-9a-f]{16}\.json$")
#: the explorer's sound (app.files.sound): a recording's extracted audio, synthesised speech
_SOUND = re.compile(r"^(?:recording-[0-9a-f]{16}|speech-[0-9a-f]{16}\.wav)$")
#: a drawn cloud's k-NN densities (app.files.density_cache)
_DENSITY = re.compile(r"^[0-9a-f]{16}\.npy$")

#: environment variable that moves the cache folder
CACHE_DIR_ENV = "LIPSPACE_CACHE_DIR"


def cache_dir() -> Path:
    """The cache folder: ``$LIPSPACE_CACHE_DIR``, else the platform's user cache folder."""
    from engine.files.userdirs import user_dir

    return user_dir("cache", CACHE_DIR_ENV)


@dataclass(frozen=True)
class CacheEntry:
    """One cached item: its path, kind (``"corpus"``, ``"audio"``, ``"manifold"``, ``"method choice"``,
    ``"sound"``, ``"density"``, ``"partial"``), synthetic talker preset ("" if unknown), size in bytes,
    and whether Lipspace wrote it (``owned``; only owned entries are ever deleted)."""

    path: Path
    kind: str
    preset: str
    size: int
    owned: bool = True


def _owned(p: Path, kind: str, root: Path) -> bool:
    """Whether Lipspace wrote ``p``: its marker (:func:`engine.files.ownership.owned`), or, for a temporary
    file of the atomic writer, a process id in its name that no longer runs."""
    if kind == "partial":
        from engine.files.placing import process_gone

        try:
            return p.is_file() and not p.is_symlink() and process_gone(p.name, p.lstat().st_mtime) and \
                bool(_ENTRY.match(p.name).group("pid"))
        except OSError:
            return False
    from engine.files.ownership import owned

    return owned(p, root)


def _size(p: Path) -> int:
    if p.is_dir() and not p.is_symlink():
        return sum(f.stat().st_size for f in p.rglob("*") if f.is_file() and not f.is_symlink())
    try:
        return p.lstat().st_size
    except OSError:
        return 0


def entries(folder=None) -> list[CacheEntry]:
    """Lipspace's entries in the cache ``folder`` (default :func:`cache_dir`), oldest first."""
    root = Path(folder) if folder is not None else cache_dir()
    out = []
    sub = root / "method-choice"
    if sub.is_dir():
        out += [CacheEntry(p, "method choice", "", _size(p), _owned(p, "method choice", root)) for p in sub.iterdir()
                if _CHOICE.match(p.name) and p.is_file() and not p.is_symlink()]
    for name, kind, pattern in (("sound", "sound", _SOUND), ("density", "density", _DENSITY)):
        sub = root / name
        if sub.is_dir():
            out += [CacheEntry(p, kind, "", _size(p), _owned(p, kind, root)) for p in sub.iterdir()
                    if pattern.match(p.name) and not p.is_symlink() and (kind == "sound" or p.is_file())]
    for sub, kind in ((root, "corpus"), (root / "manifolds", "manifold")):
        if not sub.is_dir():
            continue
        for p in sub.iterdir():
            m = _ENTRY.match(p.name)
            if not m or p.is_symlink():
                continue
            k = "partial" if p.name.startswith(".") else "audio" if p.name.endswith("-audio") else kind
            if (k == "audio") != p.is_dir():
                continue
            out.append(CacheEntry(p, k, m.group("preset") or "", _size(p), _owned(p, k, root)))
    return sorted(out, key=lambda e: (_mtime(e.path), e.path.name))


def _mtime(p: Path) -> float:
    try:
        return p.lstat().st_mtime
    except OSError:
        return 0.0


def total_bytes(folder=None) -> int:
    """Bytes taken by the entries Lipspace wrote in the cache folder."""
    return sum(e.size for e in entries(folder) if e.owned)


def newest(kind: str, preset: str, folder=None) -> list[Path]:
    """The most recently written entry of ``kind`` for ``preset`` ([] if none): the one the
    current code wrote or uses, where its key is not known here (the synthetic corpus)."""
    found = [e.path for e in entries(folder) if e.kind == kind and e.preset == preset and e.owned]
    return found[-1:]


def _remove(p: Path, root: Path) -> None:
    from engine.files.ownership import unmark

    if p.is_dir() and not p.is_symlink():
        shutil.rmtree(p, ignore_errors=True)
    else:
        p.unlink(missing_ok=True)
    if not p.exists():
        unmark(p, root)


def prune(keep, folder=None) -> list[CacheEntry]:
    """Delete the entries left behind by ``keep``: the same kind and preset, other keys.

    Parameters
    ----------
    keep : path or sequence of paths
        The current entries (just written or just used); each keeps its audio folder.
    folder : path, optional
        The cache folder (default :func:`cache_dir`).

    Returns
    -------
    list of CacheEntry
        What was deleted. Errors (a file in use, a read-only folder) leave an entry in
        place; it is tried again next time.
    """
    root = Path(folder) if folder is not None else cache_dir()
    keeps = [Path(k) for k in ([keep] if isinstance(keep, (str, Path)) else keep)]
    keep_names = {k.name for k in keeps} | {k.stem + "-audio" for k in keeps}
    found = entries(root)
    current = [e for e in found if e.path.name in keep_names]
    gone = []
    for e in found:
        if e.path.name in keep_names or e.kind == "partial" or not e.owned:
            continue
        if any(c.preset == e.preset and (c.kind == e.kind or {c.kind, e.kind} == {"corpus", "audio"})
               and c.path.parent == e.path.parent for c in current):
            _remove(e.path, root)
            if not e.path.exists():
                gone.append(e)
    return gone


def clear(folder=None) -> list[CacheEntry]:
    """Delete every entry Lipspace wrote in the cache folder (and ``manifolds/`` once empty).

    Returns what was deleted; anything else in the folder (also a file named like an
    entry that Lipspace did not write) is left alone.
    """
    root = Path(folder) if folder is not None else cache_dir()
    gone = []
    for e in entries(root):
        if not e.owned:
            continue
        _remove(e.path, root)
        if not e.path.exists():
            gone.append(e)
    for name in ("manifolds", "method-choice", "sound", "density", MARKS):
        sub = root / name
        if sub.is_dir() and not any(sub.iterdir()):
            sub.rmdir()
    return gone
