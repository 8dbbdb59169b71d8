"""Out of memory, said plainly: how much was asked for, how much the computer has, what to do.

Qt-free. The window's worker tasks (:mod:`app.workers`, :mod:`app.user_messages`) and
the command line turn any ``MemoryError`` into one sentence from :func:`memory_message`:
numpy's ``Unable to allocate 15.6 GiB for an array with shape (...)`` becomes "needed
15.6 GB more at once; this computer has 8.0 GB", followed by what reduces the need
(a landmark embedding, a lower frame rate, fewer frames).
"""
from __future__ import annotations

import os
import re

__all__ = ["memory_message", "requested_bytes", "installed_bytes", "format_bytes", "MEMORY_HINT"]

#: what lowers a build's memory, in the window's and the command line's words
MEMORY_HINT = ("Build with a landmark embedding (lipspace build --landmarks 2000), import the recording at a "
               "lower frame rate (lipspace import --resample 30), or use fewer frames.")

_UNITS = {"B": 1, "KiB": 2**10, "MiB": 2**20, "GiB": 2**30, "TiB": 2**40, "PiB": 2**50, "EiB": 2**60}
_ALLOCATE = re.compile(r"allocate ([0-9.]+) ([KMGTPE]?i?B)")


def requested_bytes(exc: BaseException) -> int | None:
    """Bytes the failed allocation asked for, when the error says (numpy's does), else None."""
    size = getattr(exc, "_total_size", None)  # numpy's _ArrayMemoryError
    if isinstance(size, int) and size > 0:
        return size
    m = _ALLOCATE.search(str(exc))
    if m and m.group(2) in _UNITS:
        return int(float(m.group(1)) * _UNITS[m.group(2)])
    return None


def installed_bytes() -> int | None:
    """Physical memory of this computer (bytes), or None where the system does not say."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return None


def format_bytes(n: int) -> str:
    """'15.6 GB' / '350 MB' (decimal units, as file managers show them)."""
    return f"{n / 1e9:.1f} GB" if n >= 1e8 else f"{n / 1e6:.0f} MB"


def memory_message(exc: BaseException, *, doing: str = "finish", hint: str = MEMORY_HINT) -> str:
    """One or two plain sentences for a ``MemoryError`` raised while ``doing`` something.

    Parameters
    ----------
    exc : BaseException
        The ``MemoryError`` (numpy's carries the size it asked for).
    doing : str
        Completes "Lipspace ran out of memory while trying to ..." (``"open corpus.npz"``).
    hint : str
        What to do instead; :data:`MEMORY_HINT` by default.

    Returns
    -------
    str
        Names the size when known, never a Python class.
    """
    need, have = requested_bytes(exc), installed_bytes()
    size = f": it needed {format_bytes(need)} more at once" if need else ""
    ram = f" (this computer has {format_bytes(have)})" if have and need else ""
    return f"Lipspace ran out of memory while trying to {doing}{size}{ram}. {hint}"
