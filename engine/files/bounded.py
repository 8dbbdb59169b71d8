"""Reading what the user hands over without letting its size decide how much memory is taken.

One reader for every file read whole (recordings, alignments, sessions, markers,
settings): :func:`read_bounded` opens only a regular file (a FIFO would block, a device
such as ``/dev/zero`` never ends; a symbolic link counts as what it points to), checks
its size against a limit before reading, and never reads more than the limit even if
the file grows meanwhile. The limit of a recording is what the computer can hold while
the recording is parsed (:func:`input_limit`): the memory this process may use (the
smaller of the physical memory and an address-space limit, ``ulimit -v``) divided by
how many times its size parsing needs. A refusal is :class:`InputTooLargeError`, which
names the file, its size and the limit.

JSON read back from files goes through :func:`parse_json`, which turns every way it can
fail (also nesting deep enough to exhaust Python's recursion) into one ``ValueError``.
"""
from __future__ import annotations

import json
import os
import stat
from pathlib import Path

__all__ = ["InputTooLargeError", "NotRegularFileError", "read_bounded", "check_bounded", "input_limit",
           "memory_budget", "format_size", "parse_json", "TEXT_EXPANSION", "BINARY_EXPANSION"]

#: how many times a text table's size parsing it needs at once (the text, its lines, the numbers)
TEXT_EXPANSION = 8
#: the same for a binary recording (its bytes, then its samples as float64)
BINARY_EXPANSION = 4


class NotRegularFileError(ValueError):
    """A path names a FIFO, socket, device or directory where a file on disk was expected."""

    def __init__(self, path, kind: str, what: str = "file"):
        self.path, self.kind = str(path), kind
        super().__init__(f"{path}: is {kind}, not a regular {what}; give a {what} on disk")


class InputTooLargeError(ValueError):
    """A file is larger than what may be read of it; the message names the file, its size and the limit."""

    def __init__(self, path, size: int, limit: int, why: str = ""):
        self.path, self.size, self.limit = str(path), int(size), int(limit)
        super().__init__(f"{path}: {format_size(size)} is more than can be read here (at most "
                         f"{format_size(limit)}{'; ' + why if why else ''})")


def format_size(n: int) -> str:
    """``n`` bytes as ``"6.0 GB"``, ``"512 kB"``, ``"37 bytes"`` (powers of 1000, as file managers show)."""
    n = int(n)
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.{1 if n < 100 * scale else 0}f} {unit}"
    return f"{n} byte{'s' * (n != 1)}"


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a pipe (FIFO)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "not a regular file"


def check_bounded(path, *, limit: int | None = None, what: str = "file", why: str = "") -> int:
    """The size of the regular file ``path`` after checking it is one and is at most ``limit`` bytes.

    Raises ``FileNotFoundError`` (no such file), :class:`NotRegularFileError` (a directory, FIFO,
    socket or device, also behind a symbolic link; nothing is opened) or
    :class:`InputTooLargeError` (``why`` says where the limit comes from).
    """
    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such {what}") from None
    if not stat.S_ISREG(st.st_mode):
        raise NotRegularFileError(path, _kind(st.st_mode), what)
    if limit is not None and st.st_size > limit:
        raise InputTooLargeError(path, st.st_size, limit, why)
    return int(st.st_size)


def read_bounded(path, *, limit: int | None = None, what: str = "file", why: str = "") -> bytes:
    """Every byte of the regular file ``path``, refused before reading when it holds more than ``limit``.

    The file is opened without blocking (a FIFO swapped in after the check cannot hang the
    read) and at most ``limit + 1`` bytes are read, so a file that grows meanwhile is
    refused too. Errors as :func:`check_bounded`.
    """
    path = Path(path)
    check_bounded(path, limit=limit, what=what, why=why)
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):  # replaced between the check and the open
            raise NotRegularFileError(path, _kind(st.st_mode), what)
        chunks, total = [], 0
        cap = None if limit is None else limit + 1
        while True:
            want = 1 << 24 if cap is None else min(1 << 24, cap - total)
            if want <= 0:
                break
            block = os.read(fd, want)
            if not block:
                break
            chunks.append(block)
            total += len(block)
        if limit is not None and total > limit:
            raise InputTooLargeError(path, max(total, st.st_size), limit, why)
        return b"".join(chunks)
    finally:
        os.close(fd)


def _proc_status(key: str) -> int | None:
    """A ``kB`` figure of ``/proc/self/status`` in bytes (Linux), else None."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def memory_budget() -> tuple[int, str]:
    """(bytes this process can still allocate at most, where that figure comes from).

    The physical memory, or, when an address-space limit (``ulimit -v``, RLIMIT_AS) is set,
    what is left of it beyond what the process has mapped already, whichever is smaller.
    """
    try:
        phys = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        phys = 16 * 10**9
    budget, source = int(phys), f"this computer's {format_size(phys)} of memory"
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        unlimited = soft == resource.RLIM_INFINITY
    except (ImportError, AttributeError, ValueError, OSError):  # Windows: no address-space limits
        soft, unlimited = 0, True
    if not unlimited and soft > 0:
        left = max(soft - (_proc_status("VmSize") or 0), 0)
        if left < budget:
            budget, source = left, f"the {format_size(soft)} address-space limit of this process (ulimit -v)"
    return budget, source


def input_limit(expansion: int = TEXT_EXPANSION) -> tuple[int, str]:
    """(largest input file read whole, why): :func:`memory_budget` over ``expansion``."""
    budget, source = memory_budget()
    return budget // max(int(expansion), 1), f"reading it needs about {expansion}x its size and {source} allows that"


def parse_json(data, *, source, what: str = "JSON"):
    """``data`` (bytes or str) parsed as JSON; ``ValueError`` naming ``source`` for anything it is not.

    Undecodable bytes, syntax errors and nesting deep enough to exhaust Python's recursion
    (a file of 100,000 ``[``) all become one message, never a traceback.
    """
    try:
        if isinstance(data, bytes):
            data = data.decode("utf-8")
        return json.loads(data)
    except UnicodeDecodeError as exc:
        raise ValueError(f"{source}: not UTF-8 text at byte {exc.start}; expected {what}") from None
    except RecursionError:
        raise ValueError(f"{source}: nested too deeply; expected {what}") from None
    except ValueError as exc:  # json.JSONDecodeError
        raise ValueError(f"{source}: not valid {what} ({exc})") from None
