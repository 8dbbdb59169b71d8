"""Memory-mapped arrays: giving the resident pages of a pass over one back to the system."""
from __future__ import annotations

import mmap

import numpy as np

__all__ = ["release_pages"]


def release_pages(a) -> None:
    """Give back the resident pages of the memory map under ``a`` (an ``np.memmap`` or a view of one).

    The pages stay in the system's file cache; reading ``a`` again pages them back in. A pass
    over a large mapped array (a finiteness check) then leaves the process's resident memory
    as it was. Does nothing for an array in memory.
    """
    base = a
    while base is not None and not isinstance(getattr(base, "_mmap", None), mmap.mmap):
        base = getattr(base, "base", None)
    mm = None if base is None else base._mmap
    if mm is None or not hasattr(mm, "madvise") or not hasattr(mmap, "MADV_DONTNEED"):
        return
    try:
        start = np.frombuffer(mm, dtype=np.uint8).ctypes.data
        lo = a.ctypes.data - start
        hi = lo + a.nbytes
        page = mmap.PAGESIZE
        lo = (lo // page) * page
        hi = min(len(mm), -(-hi // page) * page)
        if hi > lo:
            mm.madvise(mmap.MADV_DONTNEED, lo, hi - lo)
    except (ValueError, OSError, BufferError):
        pass  # an advice only
