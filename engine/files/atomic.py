"""Atomic file writing: a crash never leaves a half-written file."""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

from engine.files.placing import STALE_SECONDS as STALE_PART_SECONDS  # noqa: F401 (read by the tests and named in docs)
from engine.files.placing import process_gone

__all__ = ["atomic_write", "write_text_atomic", "write_wav_atomic"]


@contextlib.contextmanager
def atomic_write(path):
    """Yield a temporary path beside ``path``; on success rename it over ``path``.

    The temporary file keeps ``path``'s suffix so writers that look at the extension
    (numpy, matplotlib, VTK) behave as for the real name. Before the rename the file's
    data is flushed to disk (fsync), and after it the directory entry too, so a power
    loss leaves either the old or the new file, never an empty one. On any exception
    (also KeyboardInterrupt, which the command line raises for SIGTERM/SIGHUP) the
    temporary file is removed and ``path`` is left untouched.
    """
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory; give a file name to write")
    path.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale_parts(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.p{os.getpid()}-", suffix=".part" + path.suffix,
                                   dir=path.parent)
    except OSError as exc:  # a read-only or full folder: name the user's file, not the temporary one
        raise _naming(exc, path) from None
    os.close(fd)
    tmp = Path(tmp)
    try:
        yield tmp
        # mkstemp creates the file 0600; give the result the mode a plain open() would.
        with contextlib.suppress(OSError):
            os.chmod(tmp, 0o666 & ~_umask())
        _fsync(tmp)
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        if isinstance(exc, OSError) and exc.filename in (None, str(tmp)):
            raise _naming(exc, path) from None
        raise
    _fsync(path.parent, directory=True)


def _naming(exc: OSError, path) -> OSError:
    """``exc`` (disk full, permission denied ...) naming ``path``, the file the user asked for."""
    return type(exc)(exc.errno, exc.strerror or str(exc), str(path)) if exc.errno else exc


def _remove_stale_parts(path: Path) -> None:
    """Remove ``.<stem>.*.part<suffix>`` files beside ``path`` left by a killed process.

    SIGKILL (or a power cut) cannot be caught, so its temporary file stays; the next
    write to the same path removes it once the process named in it has ended (a name
    without a process id, from an older Lipspace: once it has not been modified for an
    hour, :data:`STALE_PART_SECONDS`).
    """
    for q in path.parent.glob(f".{_glob_escape(path.stem)}.*.part{_glob_escape(path.suffix)}"):
        with contextlib.suppress(OSError):
            if q.is_file() and process_gone(q.name, q.stat().st_mtime):
                q.unlink()


def _glob_escape(text: str) -> str:
    import glob

    return glob.escape(text)


def _fsync(p, *, directory: bool = False) -> None:
    """Flush ``p``'s data (or a directory's entries) to disk; a no-op where unsupported."""
    try:
        fd = os.open(p, os.O_RDONLY | (getattr(os, "O_DIRECTORY", 0) if directory else 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:  # some file systems (and Windows directories) cannot
        pass
    finally:
        os.close(fd)


def _umask() -> int:
    """The process umask, read without changing it where the OS allows (Linux /proc)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0)  # elsewhere: the classic read-by-setting, briefly process-wide
    os.umask(mask)
    return mask


def write_text_atomic(path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_write(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_wav_atomic(path, samples, rate) -> Path:
    """Write 16-bit PCM ``samples`` to the WAV file ``path`` atomically.

    Parameters
    ----------
    samples : ndarray of shape (n,) or (n, channels)
        int16 samples are written as they are; float samples are full scale at ±1
        (clipped there, rounded to int16).
    rate : float
        Sample rate in Hz (rounded to an integer).
    """
    import numpy as np
    import scipy.io.wavfile

    x = np.asarray(samples)
    if x.dtype != np.int16:
        x = np.round(np.clip(x.astype(np.float64), -1.0, 1.0) * 32767).astype(np.int16)
    with atomic_write(path) as tmp:
        scipy.io.wavfile.write(tmp, int(round(float(rate))), x)
    return Path(path)
