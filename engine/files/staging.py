"""The outputs of one command, written as one transaction: all of them or none.

A command that writes several files (a trajectory and a folder of meshes, a corpus and
its audio, a set of figures) reserves each with :class:`Outputs` before any work: an
existing file is refused unless ``force`` is given, naming the file. The command writes
to the temporary paths it gets back (hidden ``.<name>.part-*`` files and folders beside
the real ones), and :meth:`Outputs.commit` moves everything in at the end. Until then
nothing the user has is touched; if the command fails or is stopped the temporary files
are removed and the old outputs stay as they were. If moving in fails part-way (a full
or read-only disk), what was moved is moved back and the replaced files are restored,
so the result is still all or nothing.

Errors raised while writing name the user's file, never a temporary one
(:func:`user_path`).
"""
from __future__ import annotations

import contextlib
import errno
import os
import shutil
import tempfile
from pathlib import Path

__all__ = ["Outputs", "OutputExistsError", "FORCE_HINT", "user_path", "as_user_error", "committed"]

#: temporary path -> the user's path it stands for (files and folders being staged, in this process)
_STAND_IN: dict[str, str] = {}
#: user paths committed by this process (what a late stop message must not deny)
_COMMITTED: list[str] = []


def user_path(name: object) -> str | None:
    """The user's path behind a temporary path (or a file inside a temporary folder); ``name`` otherwise."""
    if name is None:
        return name
    s = str(name)
    p = Path(s)
    for q in (p, *p.parents):
        real = _STAND_IN.get(str(q))
        if real is not None:
            return str(Path(real) / p.relative_to(q)) if q != p else real
    return s


def committed() -> list[str]:
    """The outputs this process has moved into place so far."""
    return list(_COMMITTED)


def as_user_error(exc: OSError) -> OSError:
    """``exc`` with its file names mapped to the user's (:func:`user_path`)."""
    a, b = user_path(exc.filename), user_path(getattr(exc, "filename2", None))
    if a == exc.filename and b == getattr(exc, "filename2", None):
        return exc
    new = type(exc)(exc.errno, exc.strerror or str(exc), a, None, b) if b else type(exc)(exc.errno,
                                                                                         exc.strerror or str(exc), a)
    return new


#: what a refusal to overwrite advises (the command line's; the window passes its own)
FORCE_HINT = "Pass --force to replace existing files, or choose another name"


def _naming(exc: OSError, path) -> OSError:
    """``exc`` naming ``path`` (the file the user asked for) instead of whatever it named."""
    return type(exc)(exc.errno, exc.strerror or str(exc), str(path)) if exc.errno else exc


class OutputExistsError(FileExistsError):
    """An output file already exists and replacing it was not asked for.

    Attributes
    ----------
    path : str
        The existing file.
    option : str or None
        The option that named it (e.g. ``--audio-dir``), for the message.
    """

    def __init__(self, path, option: str | None = None, *, more: int = 0, hint: str = FORCE_HINT):
        self.path, self.option = str(path), option
        others = f" and {more} other file{'s' * (more != 1)}" if more else ""
        given = f" ({option})" if option else ""
        super().__init__(errno.EEXIST, f"{path}{others}{given} already exist{'s' * (not more)}; nothing was "
                         f"written. {hint}", str(path))

    def __str__(self):
        return self.strerror


class Outputs:
    """Files and folders one command writes, committed together.

    Parameters
    ----------
    force : bool
        Replace existing files (``--force``); otherwise an existing one is refused with
        :class:`OutputExistsError` when it is reserved, before any work.
    guard : callable() -> context manager, optional
        Wraps :meth:`commit` (the command line defers stop signals there, so that a
        signal arriving while files are moved in cannot leave half of them).
    hint : str
        What a refusal advises (default: pass ``--force``).

    Use as a context manager: on leaving without an error everything is committed; on
    any error (also KeyboardInterrupt) everything staged is removed.
    """

    def __init__(self, *, force: bool = False, guard=None, hint: str = FORCE_HINT):
        self.force = bool(force)
        self.guard = guard or contextlib.nullcontext
        self.hint = hint
        self._made: list[Path] = []  # parent folders created for the outputs (removed again if nothing lands)
        self._files: list[tuple[Path, Path, str | None, bool]] = []  # (target, temporary, option, force)
        # (target, temporary, pattern, option, exclusive)
        self._folders: list[tuple[Path, Path, str, str | None, bool]] = []
        self.done = False

    # ------------------------------------------------------------------ reserving
    def file(self, path, *, option: str | None = None, force: bool | None = None) -> Path:
        """Reserve the file ``path``; returns the temporary path to write it to (same suffix).

        ``force``: replace an existing file (default: the :class:`Outputs`' own); the window
        passes True for the file its save dialog confirmed."""
        target = Path(path)
        force = self.force if force is None else bool(force)
        if target.is_dir():
            raise IsADirectoryError(errno.EISDIR, "is a directory; give a file name", str(target))
        if target.exists() and not force:
            raise OutputExistsError(target, option, hint=self.hint)
        try:
            self._parents(target)
            fd, tmp = tempfile.mkstemp(prefix=f".{target.stem}.part-", suffix=target.suffix, dir=target.parent)
        except OSError as exc:  # a read-only or full folder: the user's name, not the temporary one
            raise _naming(exc, target) from None
        os.close(fd)
        os.unlink(tmp)  # writers create it (some refuse to write over an existing file)
        staged = Path(tmp)
        _STAND_IN[str(staged)] = str(target)
        self._files.append((target, staged, option, force))
        return staged

    def folder(self, path, *, pattern: str = "*", names=None, exclusive: bool = False,
               option: str | None = None) -> Path:
        """Reserve the folder ``path`` for new files; returns a temporary folder to write them into.

        At commit they are moved into ``path`` (created if missing). A file there of the same
        name is replaced with ``force``, else refused. ``exclusive``: the folder is a sequence
        (frames, blocks) whose files matching ``pattern`` are read back together, so every such
        file counts, also one the new set does not replace (refused without ``force``, removed
        with it, so that the folder holds exactly the new set). ``names``: the file names to be
        written, when known now, to refuse before any work (an exclusive folder refuses any
        ``pattern`` file then)."""
        target = Path(path)
        if target.exists() and not target.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, "exists and is not a directory", str(target))
        if not self.force and (exclusive or names is not None):
            self._refuse_existing(target, pattern, None if exclusive else set(names), option)
        try:
            self._parents(target)
            tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.part-", dir=target.parent))
        except OSError as exc:
            raise _naming(exc, target) from None
        _STAND_IN[str(tmp)] = str(target)
        self._folders.append((target, tmp, pattern, option, bool(exclusive)))
        return tmp

    def _parents(self, target: Path) -> None:
        """Create ``target``'s missing parent folders, remembering them."""
        missing = [q for q in reversed(target.parents) if not q.exists()]
        target.parent.mkdir(parents=True, exist_ok=True)
        self._made += missing

    def _refuse_existing(self, target: Path, pattern: str, names, option) -> None:
        if not target.is_dir():
            return
        clash = sorted(q for q in target.glob(pattern) if q.is_file() and (names is None or q.name in names))
        if clash:
            raise OutputExistsError(clash[0], option, more=len(clash) - 1, hint=self.hint)

    # ------------------------------------------------------------------ ending
    def __enter__(self):
        return self

    def __exit__(self, kind, exc, tb):
        if kind is None:
            self.commit()
            return False
        mapped = as_user_error(exc) if isinstance(exc, OSError) else exc  # before the stand-ins are forgotten
        self.discard()
        if mapped is not exc:
            raise mapped from None
        return False

    def discard(self) -> None:
        """Remove everything staged; the user's files stay as they were."""
        for _, tmp, _, _ in self._files:
            with contextlib.suppress(OSError):
                tmp.unlink()
            _STAND_IN.pop(str(tmp), None)
        for _, tmp, _, _, _ in self._folders:
            shutil.rmtree(tmp, ignore_errors=True)
            _STAND_IN.pop(str(tmp), None)
        if not self.done:
            for q in reversed(self._made):  # folders made for outputs that never landed
                with contextlib.suppress(OSError):
                    q.rmdir()
        self._files, self._folders, self._made = [], [], []

    def commit(self) -> list[Path]:
        """Move every staged output into place; all of them or, on failure, none (old files restored).

        Returns the user paths written. Raises OSError naming the user's file that could
        not be moved in (after the rollback), or :class:`OutputExistsError` when a file
        appeared at a reserved path meanwhile (without ``force``).
        """
        with self.guard():
            return self._commit()

    def _commit(self) -> list[Path]:
        moves = []  # (temporary, target, option, force): each new file, in order
        stale = []  # (target, option): files removed because the new set replaces them (force)
        for target, tmp, option, force in self._files:
            if not tmp.exists():  # reserved but never written (e.g. an optional output)
                continue
            moves.append((tmp, target, option, force))
        clash = []
        for target, tmp, pattern, option, exclusive in self._folders:
            new = sorted(p.name for p in tmp.iterdir())
            if target.is_dir() and exclusive:
                old = [q for q in target.glob(pattern) if q.is_file() and q.name not in set(new)]
                stale += [(q, option) for q in old] if self.force else []
                clash += [] if self.force else [(q, option) for q in old]
            moves += [(tmp / name, target / name, option, self.force) for name in new]
        clash = [(t, o) for _, t, o, force in moves if not force and t.exists()] + clash
        if clash:
            self.discard()
            raise OutputExistsError(clash[0][0], clash[0][1], more=len(clash) - 1, hint=self.hint)
        backup_dirs: dict[Path, Path] = {}
        backups = []  # (target, its backup)
        moved = []  # targets now holding new files
        made = []  # folders created here
        try:
            for target, _, _, _, _ in self._folders:
                if not target.exists():
                    target.mkdir(parents=True)
                    made.append(target)
            for target in [t for _, t, _, _ in moves if t.exists()] + [q for q, _ in stale]:
                d = backup_dirs.get(target.parent)
                if d is None:
                    d = backup_dirs[target.parent] = Path(tempfile.mkdtemp(prefix=".lipspace.part-old-",
                                                                           dir=target.parent))
                b = d / target.name
                os.replace(target, b)
                backups.append((target, b))
            for tmp, target, _, _ in moves:
                try:
                    os.replace(tmp, target)
                except OSError as exc:
                    raise type(exc)(exc.errno, exc.strerror or str(exc), str(target)) from None
                moved.append(target)
        except BaseException:
            for target in moved:
                with contextlib.suppress(OSError):
                    target.unlink()
            for target, b in backups:
                with contextlib.suppress(OSError):
                    os.replace(b, target)
            for target in made:
                with contextlib.suppress(OSError):
                    target.rmdir()
            for d in backup_dirs.values():
                shutil.rmtree(d, ignore_errors=True)
            self.discard()
            raise
        for d in backup_dirs.values():
            shutil.rmtree(d, ignore_errors=True)
        for _, tmp, _, _, _ in self._folders:
            shutil.rmtree(tmp, ignore_errors=True)
        written = [t for _, t, _, _ in moves]
        self.done = True
        self.discard()
        _COMMITTED.extend(str(t) for t in written)
        return written
