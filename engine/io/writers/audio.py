"""The sound of a Haskins / MVIEW EMA struct written out as a WAV file beside it, atomically.

An MVIEW ``.mat`` file holds its speech in the ``AUDIO`` entry
(:func:`engine.io.readers.mview.read_mview_audio`); the reader and the window find a WAV of the
same stem beside the file.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from engine.io.errors import ImportFormatError
from engine.io.readers.mview import read_mview_audio

__all__ = ["write_audio"]


def write_audio(path, wav_path=None) -> Path:
    """Write the ``AUDIO`` entry of an MVIEW file to a 16-bit PCM WAV, atomically.

    Parameters
    ----------
    path : str or Path
        The ``.mat`` file.
    wav_path : str or Path, optional
        Output file; default ``<stem>.wav`` beside ``path`` (where
        :func:`~engine.io.readers.mview.read_mview` finds it).

    Returns
    -------
    Path of the WAV written. Samples are scaled by the peak only if it exceeds 1.
    Non-finite samples (NaN, infinite) are written as silence and reported
    (:func:`engine.io.repairs.report_repair`); a signal without a finite sample is refused.
    """
    from engine.files.atomic import write_wav_atomic

    x, r = read_mview_audio(path)
    wav_path = Path(wav_path) if wav_path is not None else Path(path).with_suffix(".wav")
    x = x.astype(np.float64)
    bad = ~np.isfinite(x)
    if bad.all():
        raise ImportFormatError(path, f"the AUDIO signal has no finite sample ({x.size} samples, all NaN or "
                                "infinite); expected sound")
    if bad.any():
        x[bad] = 0.0
        from engine.io.repairs import report_repair

        where = np.flatnonzero(bad)
        report_repair(path, f"AUDIO: {where.size} of {x.size} samples are not finite (NaN or infinite), from "
                      f"{where[0] / r:.3f} s to {where[-1] / r:.3f} s; written as silence")
    peak = float(np.max(np.abs(x))) if x.size else 0.0
    if peak > 1.0:
        x = x / peak
    write_wav_atomic(wav_path, x, r)
    return wav_path
