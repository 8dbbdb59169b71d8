"""Moving finished files into place, and the temporary files a dead process left beside them.

* :func:`move_noreplace` renames a finished temporary file to its final name only if
  nothing exists there at that moment: the check and the rename are one step (Linux
  ``renameat2(RENAME_NOREPLACE)``, else a hard link, which fails when the name exists),
  so a file the user (or a second Lipspace) created while the command ran is never
  replaced. Only on a file system with neither (FAT, some network mounts) is it a check
  followed by a rename.
* :func:`output_kind` says what an existing output path is, so that a pipe, a device or
  a directory is never replaced by a regular file, even with ``--force``.
* Temporary names carry the writing process's id (:func:`temp_prefix`);
  :func:`recover_stale` removes the ones whose process is gone (SIGKILL or a power cut
  cannot be caught), and puts back a file a dead process had moved aside to replace it
  when nothing took its place (naming it in a :class:`StagingWarning`).
"""
from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
import stat
import time
import warnings
from pathlib import Path

__all__ = ["move_noreplace", "output_kind", "temp_prefix", "recover_stale", "StagingWarning", "BACKUP_PREFIX",
           "STALE_SECONDS", "process_gone"]

#: prefix of the folder holding the old files a commit replaces, until the new ones are all in
BACKUP_PREFIX = ".lipspace.part-old-"
#: temporary files without a process id in their name (older Lipspace) count as left behind after this long
STALE_SECONDS = 3600.0

_AT_FDCWD = -100
_RENAME_NOREPLACE = 1
_RENAMEAT2: list = []  # [function] once looked up; [None] where the C library has none


class StagingWarning(UserWarning):
    """Something a stopped Lipspace left behind was found and put right (the message says what)."""


def _renameat2():
    if not _RENAMEAT2:
        fn = None
        try:
            import ctypes

            fn = ctypes.CDLL(None, use_errno=True).renameat2
            fn.argtypes = (ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint)
        except (OSError, AttributeError, ImportError):  # not glibc >= 2.28 (or not Linux)
            fn = None
        _RENAMEAT2.append(fn)
    return _RENAMEAT2[0]


def move_noreplace(src, dst) -> None:
    """Rename ``src`` to ``dst``; ``FileExistsError`` (naming ``dst``) when ``dst`` exists, in the same step.

    A dangling symbolic link at ``dst`` exists too. ``src`` is gone afterwards.
    """
    src, dst = os.fspath(src), os.fspath(dst)
    fn = _renameat2()
    if fn is not None:
        import ctypes

        if fn(_AT_FDCWD, os.fsencode(src), _AT_FDCWD, os.fsencode(dst), _RENAME_NOREPLACE) == 0:
            return
        e = ctypes.get_errno()
        if e == errno.EEXIST:
            raise FileExistsError(e, os.strerror(e), dst)
        if e not in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP, errno.EOPNOTSUPP):
            raise OSError(e, os.strerror(e), dst)
    try:
        os.link(src, dst, follow_symlinks=False)
    except FileExistsError:
        raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), dst) from None
    except OSError as exc:  # no hard links here (or src is a folder): check, then rename
        if exc.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EMLINK, errno.ENOSYS,
                             errno.EXDEV, errno.EACCES, errno.EISDIR):
            raise
        if os.path.lexists(dst):
            raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), dst) from None
        os.replace(src, dst)
        return
    os.unlink(src)


def output_kind(path) -> str | None:
    """What exists at ``path``: None (nothing), ``"file"``, ``"link"`` (a symbolic link, dangling or to a
    regular file), ``"directory"``, or ``"a pipe (FIFO)"`` / ``"a socket"`` / ``"a device"``
    (also behind a link): the kinds no output may replace."""
    try:
        lst = os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None
    try:
        st = os.stat(path) if stat.S_ISLNK(lst.st_mode) else lst
    except OSError:  # a dangling link
        return "link"
    if stat.S_ISDIR(st.st_mode):
        return "directory"
    if stat.S_ISFIFO(st.st_mode):
        return "a pipe (FIFO)"
    if stat.S_ISSOCK(st.st_mode):
        return "a socket"
    if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode):
        return "a device"
    return "link" if stat.S_ISLNK(lst.st_mode) else "file"


def temp_prefix(name: str) -> str:
    """The start of a temporary name for ``name`` (a file's stem or a folder's name): ``.<name>.part-<pid>-``."""
    return f".{name}.part-{os.getpid()}-"


_PID = re.compile(r"\.(?:part-(?:old-)?|p)(\d+)-")


def process_gone(name: str, mtime: float) -> bool:
    """Whether the process that made temporary file ``name`` has ended (or, with no id in the name, it is old)."""
    m = _PID.search(name)
    if m is None:
        return time.time() - mtime > STALE_SECONDS
    pid = int(m.group(1))
    if pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (PermissionError, OverflowError, OSError):
        return False
    return False


def recover_stale(folder, names=()) -> list[str]:
    """Clear what dead processes left in ``folder`` for the outputs ``names`` (stems or folder names).

    Removes ``.<name>.part-<pid>-*`` files and folders whose process is gone (also the atomic
    writer's temporary file of such a name, ``..<name>.part-*``; older temporary
    names without a pid: once unmodified for :data:`STALE_SECONDS`), and empties the backup
    folders (:data:`BACKUP_PREFIX`) of dead commits: each old file goes back to its name when
    nothing took it, else it is removed (the new file landed). Returns what was put back,
    also issued as a :class:`StagingWarning`. Errors are ignored (tried again next time).
    """
    folder = Path(folder)
    restored: list[str] = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return restored
    # a staged name, and the atomic writer's temporary file of a staged name ('..<name>.part-<pid>-...')
    wanted = tuple(p for n in names if n for p in (f".{n}.part-", f"..{n}.part-"))
    for e in entries:
        try:
            if e.name.startswith(BACKUP_PREFIX) and e.is_dir(follow_symlinks=False):
                if not process_gone(e.name, e.stat(follow_symlinks=False).st_mtime):
                    continue
                for old in Path(e.path).iterdir():
                    target = folder / old.name
                    if os.path.lexists(target):
                        _remove(old)
                        continue
                    move_noreplace(old, target)
                    restored.append(str(target))
                shutil.rmtree(e.path, ignore_errors=True)
            elif wanted and e.name.startswith(wanted):
                if process_gone(e.name, e.stat(follow_symlinks=False).st_mtime):
                    _remove(Path(e.path))
        except OSError:
            continue
    for p in restored:
        warnings.warn(StagingWarning(f"{p} was put back: a Lipspace that was stopped while replacing it had moved "
                                     "it aside"), stacklevel=3)
    return restored


def _remove(p: Path) -> None:
    if p.is_dir() and not p.is_symlink():
        shutil.rmtree(p, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            p.unlink()
