"""C3D motion-capture marker files, read with the ``c3d`` library."""
from __future__ import annotations

import io
import warnings
from pathlib import Path

import numpy as np

from engine.files.bounded import BINARY_EXPANSION
from engine.io._util import check_rate, one_utterance_corpus, plausible_rate, read_bytes, sidecar_audio
from engine.io._util import fill_gaps as _fill_gaps
from engine.io.errors import ImportFormatError
from engine.io.readers.alignment import resolve_alignment
from engine.io.repairs import report_repair, reports_repairs

__all__ = ["read_c3d"]

#: millimetres per unit for POINT:UNITS values
_UNITS = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "dm": 100.0, "in": 25.4}


def _select(labels, markers, path):
    if markers is None:
        return list(range(len(labels)))
    idx = []
    low = [lab.lower() for lab in labels]
    for m in markers:
        if isinstance(m, (int, np.integer)):
            if not 0 <= m < len(labels):
                raise ImportFormatError(path, f"marker index {m} is out of range; the file has {len(labels)} markers")
            idx.append(int(m))
        elif str(m).lower() in low:
            idx.append(low.index(str(m).lower()))
        else:
            raise ImportFormatError(path, f"has no marker {m!r}; its markers are {labels[:20]}")
    return idx


@reports_repairs
def read_c3d(path, *, markers=None, rate: float | None = None, alignment=None, tier: str | None = None,
             fill_gaps: bool = True, to_mm: bool = True):
    """A C3D marker file as a 3-D corpus.

    Parameters
    ----------
    path : str or Path
    markers : sequence of str or int, optional
        Markers to keep (labels, case-insensitive, or indices), in order; all by default.
    rate : float, optional
        Only checked against the file's point rate.
    alignment : None, False, path or sequence of PhoneInterval
        Phones; by default ``<stem>.TextGrid`` / ``.lab`` beside the file.
    tier : str, optional
    fill_gaps : bool
        Interpolate samples the file marks invalid (residual -1) or not finite; else raise.
    to_mm : bool
        Convert coordinates to mm using ``POINT:UNITS`` (mm, cm, m, in); unknown units are kept.

    Returns
    -------
    Corpus
        One utterance named after the file; points named after the marker labels.
    """
    import c3d

    path = Path(path)
    data = read_bytes(path, expansion=BINARY_EXPANSION)
    if len(data) < 512 or data[1] != 0x50:
        raise ImportFormatError(path, f"byte 2 is {data[1:2]!r}, file size {len(data)}; expected a C3D file "
                                "(a 512-byte header whose second byte is 0x50)")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            reader = c3d.Reader(io.BytesIO(data))
            n_points = int(reader.point_used)
            first, last = int(reader.first_frame), int(reader.last_frame)
            point_rate = float(reader.point_rate)
            scale = float(reader.point_scale)
            n_analog = int(reader.analog_used) * int(reader.analog_per_frame)
            labels = [str(s).strip() for s in reader.point_labels] if reader.get("POINT:LABELS") else []
            units_p = reader.get("POINT:UNITS")
            units = units_p.string_value.strip().lower() if units_p is not None else "mm"
        except ImportFormatError:
            raise
        except Exception as exc:
            raise ImportFormatError(path, f"cannot read the C3D header or parameters ({exc or 'damaged'})") from None
        if n_points < 1:
            raise ImportFormatError(path, "has no 3-D points (POINT:USED is 0); expected marker trajectories")
        n_frames = last - first + 1
        frame_bytes = n_points * 4 * (4 if scale < 0 else 2) + n_analog * (4 if scale < 0 else 2)
        if n_frames < 2:
            raise ImportFormatError(path, f"the header gives frames {first}..{last}; expected at least 2 frames")
        whole = max(0, len(data) - (int(reader.header.data_block) - 1) * 512) // frame_bytes
        if whole < n_frames:
            raise ImportFormatError(path, f"the data holds {whole} whole frames of {frame_bytes} bytes; the header "
                                    f"promises frames {first}..{last} ({n_frames}). Truncated file?", frame=whole)
        point_rate = plausible_rate(path, point_rate, "POINT:RATE")
        labels = (labels + [f"M{k}" for k in range(len(labels), n_points)])[:n_points]
        xyz = np.empty((n_frames, n_points, 3), np.float64)
        bad = np.zeros((n_frames, n_points), bool)
        got = 0
        try:
            for k, (_, pts, _) in enumerate(reader.read_frames(copy=False)):
                if k >= n_frames:
                    break
                xyz[k] = pts[:, :3]
                bad[k] = pts[:, 3] < 0
                got = k + 1
        except Exception as exc:
            raise ImportFormatError(path, f"cannot decode the frame data ({exc or 'damaged'})",
                                    frame=got) from None
    eof = [w for w in caught if "end of file" in str(w.message).lower()]
    if got < n_frames or eof:
        raise ImportFormatError(path, f"the data ends after {got} of {n_frames} frames; truncated file?", frame=got)
    native = check_rate(path, point_rate, rate)
    idx = _select(labels, markers, path)
    if len({labels[i] for i in idx}) < len(idx):
        names = [f"{labels[i]}#{i}" for i in idx]
        clash = sorted({labels[i] for i in idx if [labels[j] for j in idx].count(labels[i]) > 1})
        report_repair(path, f"markers share the label(s) {', '.join(repr(c) for c in clash)} (POINT:LABELS); "
                      "renamed <label>#<marker index> to tell them apart")
    else:
        names = [labels[i] for i in idx]
    factor = _UNITS.get(units, 1.0) if to_mm else 1.0
    X = xyz[:, idx].reshape(n_frames, -1) * factor
    miss = np.repeat(bad[:, idx], 3, axis=1)
    frames = _fill_gaps(X, miss, path=path, names=[f"{n}_{a}" for n in names for a in "xyz"], fill=fill_gaps,
                        flagged="marked invalid (negative residual)")
    phones, _ = resolve_alignment(path, alignment, tier=tier)
    return one_utterance_corpus(path, frames, native, dims=3, phones=phones, point_names=names,
                                audio=sidecar_audio(path), units="mm" if (to_mm and units in _UNITS) or units == "mm"
                                else "")
