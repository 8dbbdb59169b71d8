"""Articulograph exports: Carstens AG500 / AG501 ``.pos`` binaries and NDI Wave TSV.

``.pos`` (AG500, AG501): little-endian float32 samples, ``channels x 7`` values per
frame (x, y, z, phi, theta, rms, extra). AG501 files start with a text header::

    AG50xDATA_V002
    00000275                 # header length in bytes, data start there
    NumberOfChannels=16
    SamplingFrequencyHz=250
    ...

AG500 files have no header (12 channels at 200 Hz, or the layout's). The 6th value of
each channel, ``rms``, is the residual of the position fit: kept as the sensor's quality
(:mod:`engine.recordings.signals.quality`; 0 in unused channels). NDI Wave TSV exports
have a header row: a ``Time`` (or ``Wav Time``) column (seconds, or milliseconds when
the step is at least half a unit) and per sensor a ``Sensor N Id`` column, optionally
a ``Status`` or ``State`` column (rows not ``OK`` are dropouts), ``Tx Ty Tz`` (then the
quaternion ``Q0 Qx Qy Qz``, ignored) and a numeric ``Error``, ``RMS`` or ``Quality``
column (the sensor's fit residual, kept as its quality).

Both return a 3-D corpus through a layout (:mod:`engine.recordings.layouts`) that names the
channels and gives their roles; the built-in ``ag500`` / ``ag501`` / ``wave`` layouts
name them ``ch1, ch2, ...``.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from engine.io._util import decode_text, plausible_rate, read_bytes, uniform_rate
from engine.io.errors import ImportFormatError
from engine.io.readers.sensor_matrix import corpus_from_matrix
from engine.io.repairs import reports_repairs
from engine.recordings.layouts import LayoutError, get_layout

__all__ = ["read_pos", "read_wave", "POS_MAGIC"]

POS_MAGIC = b"AG50xDATA"


def _layout(path, layout, default):
    try:
        return get_layout(layout if layout is not None else default)
    except LayoutError as exc:
        raise ImportFormatError(path, str(exc)) from None


@reports_repairs
def read_pos(path, *, layout=None, rate: float | None = None, points=None, alignment=None, tier=None,
             fill_gaps: bool = True):
    """A Carstens AG500 / AG501 ``.pos`` file as a 3-D corpus.

    Parameters
    ----------
    path : str or Path
    layout : str, Path or Layout, optional
        Names and roles of the channels (default: ``ag501`` when the file has an
        ``AG50xDATA`` header, else ``ag500``). The header's channel count and rate win
        over the layout's.
    rate : float, optional
        Frame rate when the file has no header (default: the layout's).
    points, alignment, tier, fill_gaps : see :func:`engine.io.readers.matrix.read_matrix`

    Returns
    -------
    Corpus
    """
    path = Path(path)
    data = read_bytes(path)
    lay = _layout(path, layout, "ag501" if data.startswith(POS_MAGIC) else "ag500")
    start, n_ch, hdr_rate = 0, len(lay.sensors), None
    if data.startswith(POS_MAGIC):
        lines = data[:64].split(b"\n")
        try:
            start = int(lines[1].strip())
        except (IndexError, ValueError):
            raise ImportFormatError(path, f"AG50x header: line 2 is {lines[1:2]!r}; expected the header length in "
                                    "bytes") from None
        if not 0 < start <= len(data):
            raise ImportFormatError(path, f"AG50x header claims {start} bytes but the file has {len(data)}")
        fields = _pos_header(data[:start].decode("latin-1"))
        if "NumberOfChannels" in fields:
            value, line = fields["NumberOfChannels"]
            try:
                n_ch = int(value)
            except ValueError:
                raise ImportFormatError(path, f"NumberOfChannels is {value[:30]!r}; expected a whole number of "
                                        "channels", line=line) from None
        if "SamplingFrequencyHz" in fields:
            value, line = fields["SamplingFrequencyHz"]
            hdr_rate = plausible_rate(path, value, "SamplingFrequencyHz", line=line)
    if n_ch < 1:
        raise ImportFormatError(path, f"header gives {n_ch} channels; expected at least 1")
    try:
        lay = lay.with_channels(n_ch)
    except LayoutError as exc:
        raise ImportFormatError(path, str(exc)) from None
    if lay.values != 7:
        raise ImportFormatError(path, f"layout {lay.name!r} has {lay.values} values per sensor; .pos files hold 7")
    body = len(data) - start
    per_frame = 4 * n_ch * 7
    if body % per_frame:
        raise ImportFormatError(path, f"{body} data bytes are not a whole number of frames of {n_ch} channels x 7 "
                                f"float32 ({per_frame} bytes); truncated file, or wrong channel count "
                                "(give a layout with one sensor per channel)", frame=body // per_frame)
    M = np.frombuffer(data, "<f4", body // 4, start).reshape(-1, n_ch * 7)
    if hdr_rate is not None and rate is not None and abs(hdr_rate - float(rate)) > 1e-6 * hdr_rate:
        raise ImportFormatError(path, f"the header says {hdr_rate:g} Hz but a rate of {float(rate):g} Hz was given "
                                "(--rate); to change the rate, resample (lipspace import --resample)")
    r = hdr_rate if hdr_rate is not None else (rate if rate is not None else lay.rate)
    if r is None:
        raise ImportFormatError(path, "no rate in the file or the layout; give one (lipspace import --rate HZ)")
    r = plausible_rate(path, r, "the frame rate" if hdr_rate is None else "SamplingFrequencyHz")
    return corpus_from_matrix(path, M, lay, rate=float(r), points=points, fill_gaps=fill_gaps,
                              alignment=alignment, tier=tier)


def _pos_header(text: str) -> dict:
    """``{key: (value, line)}`` of the ``key=value`` lines of an AG50x header."""
    out = {}
    for i, raw in enumerate(text.split("\n"), start=1):
        key, eq, value = raw.partition("=")
        if eq and key.strip():
            out[key.strip()] = (value.strip().strip("\x00"), i)
    return out


_SENSOR = re.compile(r"sensor\s*(\d+)\s*id", re.I)


@reports_repairs
def read_wave(path, *, layout=None, rate: float | None = None, points=None, alignment=None, tier=None,
              fill_gaps: bool = True):
    """An NDI Wave TSV export as a 3-D corpus.

    Parameters
    ----------
    path : str or Path
    layout : str, Path or Layout, optional
        Names and roles of the sensors in the file's order (default ``wave``:
        ``ch1, ch2, ...``).
    rate : float, optional
        Only checked against the ``Time`` column.
    points, alignment, tier, fill_gaps : see :func:`engine.io.readers.matrix.read_matrix`
    """
    path = Path(path)
    lay = _layout(path, layout, "wave")
    text = decode_text(read_bytes(path), path)
    lines = text.splitlines()
    hdr_no = next((i for i, ln in enumerate(lines) if ln.strip()), None)
    if hdr_no is None:
        raise ImportFormatError(path, "is empty; expected an NDI Wave TSV export")
    head = [h.strip() for h in lines[hdr_no].split("\t")]
    low = [h.lower() for h in head]
    t_col = next((i for i, h in enumerate(low) if h in ("time", "time (s)", "time(s)", "time [s]", "wav time")),
                 None)
    starts = [i for i, h in enumerate(head) if _SENSOR.fullmatch(h.strip())]
    if t_col is None or not starts:
        raise ImportFormatError(path, f"header {head[:8]} has no 'Time' column or no 'Sensor N Id' columns; "
                                "expected an NDI Wave TSV export", line=hdr_no + 1)
    blocks = []
    for k, s in enumerate(starts):
        end = starts[k + 1] if k + 1 < len(starts) else len(head)
        cols = {h.lower(): j for j, h in enumerate(head[s:end], s)}
        try:
            xyz = [next(j for h, j in cols.items() if h.rstrip() == f"t{a}" or h.endswith(f" t{a}")) for a in "xyz"]
        except StopIteration:
            raise ImportFormatError(path, f"sensor block {head[s]!r} has no Tx, Ty, Tz columns",
                                    line=hdr_no + 1) from None
        status = next((j for h, j in cols.items() if "status" in h or h.rstrip() == "state"
                       or h.endswith(" state")), None)
        err = next((j for h, j in cols.items() if h.rstrip() in ("error", "rms", "rms error", "quality")
                    or h.endswith((" error", " rms", " quality"))), None)
        blocks.append((xyz, status, err))
    n_s = len(blocks)
    try:
        lay = lay.with_channels(n_s) if lay.format == "wave" and lay.name == "wave" else lay
    except LayoutError as exc:
        raise ImportFormatError(path, str(exc)) from None
    if len(lay.sensors) != n_s:
        raise ImportFormatError(path, f"has {n_s} sensors but layout {lay.name!r} names {len(lay.sensors)}; "
                                "give one 'sensor' line per Wave sensor, in the file's order")
    has_q = any(e is not None for _, _, e in blocks)
    times, rows, bad, quality = [], [], [], []
    for ln in range(hdr_no + 1, len(lines)):
        raw = lines[ln]
        if not raw.strip():
            continue
        tok = raw.split("\t")
        if len(tok) < len(head) or any(t.strip() for t in tok[len(head):]):
            raise ImportFormatError(path, f"has {len(tok)} fields; the header has {len(head)}", line=ln + 1)
        try:
            times.append(float(tok[t_col]))
        except ValueError:
            raise ImportFormatError(path, f"Time is {tok[t_col][:30]!r}; expected a number", line=ln + 1) from None
        vals: list[float]
        q: list[float]
        vals, miss, q = [], [], []
        for xyz, st, err in blocks:
            ok = st is None or tok[st].strip().upper() in ("OK", "0", "")
            for j in xyz + ([err] if err is not None else []):
                cell = tok[j].strip()
                try:
                    (q if j == err else vals).append(float(cell) if cell and cell.lower() != "nan" else np.nan)
                except ValueError:
                    raise ImportFormatError(path, f"column {j + 1} ({head[j]}) is {cell[:30]!r}; expected a number",
                                            line=ln + 1) from None
            if has_q and err is None:
                q.append(0.0)  # this sensor has no error column: not measured
            miss.append(not ok)
        rows.append(vals)
        bad.append(miss)
        quality.append(q)
    if len(rows) < 2:
        raise ImportFormatError(path, f"holds {len(rows)} data rows; expected at least 2")
    t = np.array(times)
    if np.median(np.diff(t)) >= 0.5:  # milliseconds
        t = t / 1000.0
    native = uniform_rate(t, path)
    if rate is not None and abs(float(rate) - native) > 1e-3 * native:
        raise ImportFormatError(path, f"the Time column says {native:g} Hz but a rate of {float(rate):g} Hz was "
                                "given (--rate); leave the rate out, or resample (lipspace import --resample)")
    from dataclasses import replace

    lay3 = replace(lay, values=3, xyz=(0, 1, 2), quality=None)
    return corpus_from_matrix(path, np.array(rows), lay3, rate=native, points=points, fill_gaps=fill_gaps,
                              alignment=alignment, tier=tier, missing=np.array(bad, bool), flagged="status not OK",
                              quality=np.array(quality, np.float64) if has_q else None, quality_measure="error")

