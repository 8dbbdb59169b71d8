"""EST Track files (Edinburgh Speech Tools; MOCHA-TIMIT's ``.ema`` layout), written atomically.

The header (``EST_File Track``, ``DataType``, ``ByteOrder``, ``NumFrames``, ``NumChannels``,
``BreaksPresent``, ``Channel_k <name>``, closed by ``EST_Header_End``) and per frame the time,
the break/valid value and the channels, binary float32 or ASCII:
:mod:`engine.io.readers.ema` reads it back.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["write_est_track"]


def write_est_track(path, times, values, names, *, valid=None, binary: bool = True, byte_order: str = "01"):
    """Write an EST Track file (the layout :func:`engine.io.readers.ema.read_est_track` reads), atomically.

    Parameters
    ----------
    path : str or Path
    times : array of shape (n_frames,), seconds
    values : array of shape (n_frames, n_channels)
    names : sequence of str, one per channel
    valid : bool array of shape (n_frames,), optional
        Written as the break column (1 valid, 0 break); all valid by default.
    binary : bool
        Binary float32 data (True) or ASCII.
    byte_order : {"01", "10"}
        Little- or big-endian binary data.
    """
    from engine.files.atomic import atomic_write

    times = np.asarray(times, dtype=np.float64).ravel()
    values = np.asarray(values, dtype=np.float64)
    n = times.shape[0]
    if values.ndim != 2 or values.shape[0] != n or len(names) != values.shape[1]:
        raise ValueError(f"values {values.shape} must be (n_frames={n}, n_channels={len(names)})")
    if byte_order not in ("01", "10"):
        raise ValueError(f"byte_order={byte_order!r}; expected '01' (little) or '10' (big)")
    valid = np.ones(n, bool) if valid is None else np.asarray(valid, bool)
    step = float(np.median(np.diff(times))) if n > 1 else 0.0
    head = ["EST_File Track", f"DataType {'binary' if binary else 'ascii'}"]
    if binary:
        head.append(f"ByteOrder {byte_order}")
    head += [f"NumFrames {n}", f"NumChannels {values.shape[1]}", "NumAuxChannels 0", f"EqualSpace {int(step > 0)}",
             "BreaksPresent true", "CommentChar ;", ""]
    head += [f"Channel_{k} {nm}" for k, nm in enumerate(names)]
    head.append("EST_Header_End")
    table = np.column_stack([times, valid.astype(np.float64), values])
    with atomic_write(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(("\n".join(head) + "\n").encode("ascii"))
            if binary:
                fh.write(table.astype(("<" if byte_order == "01" else ">") + "f4").tobytes())
            else:
                for row in table:
                    fh.write((" ".join(f"{v:.6f}" for v in row) + "\n").encode("ascii"))
    return Path(path)
