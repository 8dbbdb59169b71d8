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

Every output is checked against the command's inputs and its other outputs when it is
reserved (:class:`OutputClashError`: a file written twice, or over an input, whatever
derived it: the table ``--praat`` writes beside its TextGrid, the WAV beside a ``.glb``),
and a pipe, socket, device or directory is never replaced by a file, ``force`` or not.
The no-replace rule holds at the final rename too (:func:`engine.files.placing.move_noreplace`):
a file that appeared while the command ran is left alone and the commit refused.
Temporary names carry the process id, so the next reservation beside them removes what a
killed process left (:func:`engine.files.placing.recover_stale`).

Errors raised while writing name the user's file, never a temporary one
(:func:`user_path`).
"""
from __future__ import annotations

import contextlib
import errno
import fnmatch
import os
import shutil
import tempfile
from pathlib import Path

from engine.files.placing import BACKUP_PREFIX, move_noreplace, output_kind, recover_stale, temp_prefix

__all__ = ["Outputs", "OutputRefusedError", "OutputExistsError", "OutputClashError", "FORCE_HINT", "user_path",
           "as_user_error", "committed"]

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


def _real(p) -> str:
    """``p`` made absolute with every symbolic link resolved (also for a file not there yet), for comparing."""
    return os.path.normcase(os.path.realpath(os.fspath(p)))


def _naming(exc: OSError, path) -> OSError:
    """``exc`` naming ``path`` (the file the user asked for) instead of whatever it named."""
    return type(exc)(exc.errno, exc.strerror or str(exc), str(path)) if exc.errno else exc


class OutputRefusedError(OSError):
    """An output that cannot be written where it was asked for; the message says why and what to do."""

    def __init__(self, path, message: str, code: int = errno.EINVAL):
        super().__init__(code, message, str(path))

    def __str__(self):
        return self.strerror


class OutputClashError(OutputRefusedError):
    """Two outputs of one command name the same file, or an output names one of its inputs."""


class OutputExistsError(OutputRefusedError, FileExistsError):
    """An output file already exists and replacing it was not asked for.

    Attributes
    ----------
    path : str
        The existing file.
    option : str or None
        The option that named it (e.g. ``--audio-dir``), for the message.
    """

    def __init__(self, path, option: str | None = None, *, more: int = 0, hint: str = FORCE_HINT,
                 meanwhile: bool = False):
        self.path, self.option = str(path), option
        others = f" and {more} other file{'s' * (more != 1)}" if more else ""
        given = f" ({option})" if option else ""
        if meanwhile:
            text = (f"{path}{others}{given} appeared while the command ran (another program wrote "
                    f"{'them' if more else 'it'}); left as {'they are' if more else 'it is'} and nothing was written. "
                    f"{hint}")
        else:
            text = f"{path}{others}{given} already exist{'s' * (not more)}; nothing was written. {hint}"
        super().__init__(path, text, errno.EEXIST)


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
    inputs : iterable of (str, path), optional
        The command's inputs as ``(option, path)``: no output may be one of them (nor, for a
        folder, hold one among the files it writes). More can be added with :meth:`input`.

    Use as a context manager: on leaving without an error everything is committed; on
    any error (also KeyboardInterrupt) everything staged is removed.
    """

    def __init__(self, *, force: bool = False, guard=None, hint: str = FORCE_HINT, inputs=()):
        self.force = bool(force)
        self.guard = guard or contextlib.nullcontext
        self.hint = hint
        self._inputs: list[tuple[str, Path]] = []
        #: what is reserved: (kind "file" | "folder", real path, pattern, names, option, path as given)
        self._reserved: list[tuple[str, str, str, object, str | None, Path]] = []
        for option, path in inputs:
            self.input(path, option=option)
        self._made: list[Path] = []  # parent folders created for the outputs (removed again if nothing lands)
        self._files: list[tuple[Path, Path, str | None, bool]] = []  # (target, temporary, option, force)
        # (target, temporary, pattern, option, exclusive)
        self._folders: list[tuple[Path, Path, str, str | None, bool]] = []
        self.done = False

    # ------------------------------------------------------------------ reserving
    def input(self, path, *, option: str | None = None) -> None:
        """Note ``path`` as one of the command's inputs (read, never written): no output may be it."""
        if path is None or str(path) == "":
            return
        p = Path(path)
        self._inputs.append((option or "an input", p))
        for kind, real, pattern, names, opt, given in self._reserved:
            if self._holds(kind, real, pattern, names, p):
                raise self._clash_input(given, opt, option or "an input", p)

    def file(self, path, *, option: str | None = None, force: bool | None = None) -> Path:
        """Reserve the file ``path``; returns the temporary path to write it to (same suffix).

        ``force``: replace an existing file (default: the :class:`Outputs`' own); the window
        passes True for the file its save dialog confirmed. Never replaced, ``force`` or not:
        a directory, a pipe, a socket or a device; a file that is an input of the command or
        that another output of it writes (:class:`OutputClashError`)."""
        target = Path(path)
        force = self.force if force is None else bool(force)
        kind = output_kind(target)
        if kind == "directory":
            raise IsADirectoryError(errno.EISDIR, "is a directory; give a file name", str(target))
        if kind not in (None, "file", "link"):
            raise OutputRefusedError(target, f"{target}{f' ({option})' if option else ''} is {kind}, not a regular "
                                     "file; Lipspace writes only regular files (--force replaces only those). "
                                     "Choose a file name")
        self._check_clash("file", target, "", None, option)
        if kind is not None and not force:
            raise OutputExistsError(target, option, hint=self.hint)
        try:
            self._parents(target)
            recover_stale(target.parent, [target.stem])
            fd, tmp = tempfile.mkstemp(prefix=temp_prefix(target.stem), suffix=target.suffix, dir=target.parent)
        except OSError as exc:  # a read-only or full folder: the user's name, not the temporary one
            raise _naming(exc, target) from None
        os.close(fd)
        os.unlink(tmp)  # writers create it (some refuse to write over an existing file)
        staged = Path(tmp)
        _STAND_IN[str(staged)] = str(target)
        self._files.append((target, staged, option, force))
        self._reserved.append(("file", _real(target), "", None, option, target))
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
        names = None if names is None else set(names)
        self._check_clash("folder", target, pattern, None if exclusive else names, option)
        if not self.force and (exclusive or names is not None):
            self._refuse_existing(target, pattern, None if exclusive else names, option)
        try:
            self._parents(target)
            recover_stale(target.parent, [target.name])
            tmp = Path(tempfile.mkdtemp(prefix=temp_prefix(target.name), dir=target.parent))
        except OSError as exc:
            raise _naming(exc, target) from None
        _STAND_IN[str(tmp)] = str(target)
        self._folders.append((target, tmp, pattern, option, bool(exclusive)))
        self._reserved.append(("folder", _real(target), pattern, None if exclusive else names, option, target))
        return tmp

    # ------------------------------------------------------------------ clashes
    @staticmethod
    def _holds(kind, real, pattern, names, p: Path) -> bool:
        """Whether the output reserved as (``kind``, ``real``, ``pattern``, ``names``) writes the path ``p``."""
        rp = _real(p)
        if rp == real:
            return True
        if kind == "folder" and os.path.dirname(rp) == real:
            name = os.path.basename(rp)
            return name in names if names is not None else fnmatch.fnmatch(name, pattern)
        return False

    def _check_clash(self, kind, target: Path, pattern, names, option) -> None:
        real = _real(target)
        for okind, oreal, opattern, onames, oopt, ogiven in self._reserved:
            same = real == oreal or self._holds(okind, oreal, opattern, onames, target) or \
                self._holds(kind, real, pattern, names, ogiven)
            if same:
                who = f"by {oopt} and by {option}" if oopt and option and oopt != option else \
                    f"by {option or oopt}" if option or oopt else ""
                raise OutputClashError(target, f"{ogiven if kind == 'folder' else target} would be written twice"
                                       f"{' (' + who + ')' if who else ''}; nothing was written. Give each output "
                                       "its own name")
        for iopt, p in self._inputs:
            if self._holds(kind, real, pattern, names, p) or (p.is_dir() and _real(p) == real):
                raise self._clash_input(target, option, iopt, p)

    @staticmethod
    def _clash_input(target, option, input_option, p) -> OutputClashError:
        given = f"{option} {target}" if option else str(target)
        also = f" ({input_option} {p})" if str(p) != str(target) else f" ({input_option})"
        return OutputClashError(target, f"{given} is also an input of the command{also}; writing it would destroy "
                                "the input. Choose another output name")

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
        for _, t, o, _force in moves:  # what changed at the outputs while the command ran
            kind = output_kind(t)
            if kind not in (None, "file", "link"):
                self.discard()
                raise OutputRefusedError(t, f"{t}{f' ({o})' if o else ''} became {kind} while the command ran; "
                                         "it was left as it is and nothing was written")
        clash = [(t, o) for _, t, o, force in moves if not force and os.path.lexists(t)] + clash
        if clash:
            self.discard()
            raise OutputExistsError(clash[0][0], clash[0][1], more=len(clash) - 1, hint=self.hint, meanwhile=True)
        backup_dirs: dict[Path, Path] = {}
        backups = []  # (target, its backup)
        moved = []  # targets now holding new files
        made = []  # folders created here
        try:
            for target, _, _, _, _ in self._folders:
                if not target.exists():
                    target.mkdir(parents=True)
                    made.append(target)
            for target in [t for _, t, _, _ in moves if os.path.lexists(t)] + [q for q, _ in stale]:
                d = backup_dirs.get(target.parent)
                if d is None:
                    d = backup_dirs[target.parent] = Path(tempfile.mkdtemp(prefix=f"{BACKUP_PREFIX}{os.getpid()}-",
                                                                           dir=target.parent))
                b = d / target.name
                os.replace(target, b)
                backups.append((target, b))
            for tmp, target, option, _ in moves:
                try:  # nothing may be at the name now: the check and the rename are one step
                    move_noreplace(tmp, target)
                except FileExistsError:
                    raise OutputExistsError(target, option, hint=self.hint, meanwhile=True) from None
                except OSError as exc:
                    raise type(exc)(exc.errno, exc.strerror or str(exc), str(target)) from None
                moved.append(target)
        except BaseException:
            for target in moved:
                with contextlib.suppress(OSError):
                    target.unlink()
            for target, b in backups:
                with contextlib.suppress(OSError):
                    move_noreplace(b, target)
            for target in made:
                with contextlib.suppress(OSError):
                    target.rmdir()
            for d in backup_dirs.values():  # only once empty: an old file that could not go back stays there
                with contextlib.suppress(OSError):
                    d.rmdir()
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
