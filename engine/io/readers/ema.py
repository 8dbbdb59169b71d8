"""MOCHA-TIMIT electromagnetic articulography (``.ema``): EST Track files and ASCII tables.

Two layouts are read:

* **EST Track** (Edinburgh Speech Tools), binary or ASCII: a text header
  (``EST_File Track``, ``DataType binary|ascii``, ``ByteOrder 01|10``, ``NumFrames``,
  ``NumChannels``, optional ``BreaksPresent``, ``Channel_k <name>`` lines) closed by
  ``EST_Header_End`` and a newline, then per frame: time (float32), a break/valid
  value (float32, only when ``BreaksPresent`` is in the header; 0 = break) and
  ``NumChannels`` float32 values. ``ByteOrder 01`` is little-endian, anything else
  big-endian, as in EST's own loader.
* **ASCII table** (the MOCHAtools conversion): whitespace columns
  ``time valid c0 .. c19`` with the channels in MOCHA's order (:data:`MOCHA_CHANNELS`).

Values are in 1/100 mm (MOCHA); ``scale`` converts them to mm. The result is a 2-D
corpus (``dims=2``, x = front-back, y = up-down, as the sensors are measured in the
mid-sagittal plane) of the chosen sensors, at the file's own rate (500 Hz for MOCHA).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from engine._deprecated import deprecated_names
from engine.io._util import (
    check_rate,
    decode_text,
    one_utterance_corpus,
    parse_floats,
    read_bytes,
    sidecar_audio,
    uniform_rate,
)
from engine.io._util import fill_gaps as _fill_gaps
from engine.io.errors import ImportFormatError
from engine.io.readers.alignment import resolve_alignment
from engine.io.repairs import reports_repairs

__all__ = ["read_ema", "read_est_track", "MOCHA_CHANNELS", "MOCHA_SENSORS", "LIP_SENSORS"]

# the writer moved to engine.io.writers.est_track; this old home still gives it, with a warning
__getattr__ = deprecated_names(__name__, {"write_est_track": ("engine.io.writers.est_track", "write_est_track")})

#: MOCHA's 20 channels in file order (MOCHAread.m): sensor_axis. 'S15' is a coil the
#: MOCHAtools documentation leaves unnamed.
MOCHA_CHANNELS = ("UI_x", "LI_x", "UL_x", "LL_x", "TT_x", "UI_y", "LI_y", "UL_y", "LL_y", "TT_y",
                  "TB_x", "TD_x", "V_x", "S15_x", "BN_x", "TB_y", "TD_y", "V_y", "S15_y", "BN_y")
#: sensors: upper incisor, lower incisor (jaw), upper lip, lower lip, tongue tip/body/dorsum,
#: velum, unnamed, bridge of nose (reference)
MOCHA_SENSORS = ("UI", "LI", "UL", "LL", "TT", "TB", "TD", "V", "S15", "BN")
#: default selection: the lips and the jaw (lower incisor)
LIP_SENSORS = ("UL", "LL", "LI")

_HEADER_END = b"EST_Header_End"
_AXIS = re.compile(r"^(?P<s>.+?)[_\-\s.]?(?P<a>[xyXY])$")


# ---------------------------------------------------------------------------- EST Track
def _parse_est_header(data: bytes, path):
    end = data.find(_HEADER_END)
    if end < 0:
        raise ImportFormatError(path, "no 'EST_Header_End' line; expected an EST Track header closed by it")
    nl = data.find(b"\n", end)
    body_start = len(data) if nl < 0 else nl + 1
    text = decode_text(data[:end], path)
    lines = text.split("\n")
    if not lines or lines[0].strip() != "EST_File Track":
        raise ImportFormatError(path, f"starts with {lines[0].strip()[:40]!r}; expected 'EST_File Track'", line=1)
    hdr, names, comment = {}, {}, ";"
    for i, raw in enumerate(lines[1:], start=2):
        s = raw.strip()
        if not s or s.startswith(comment):
            continue
        key, _, value = s.partition(" ")
        value = value.strip()
        if key.startswith("Channel_"):
            try:
                k = int(key[len("Channel_"):])
            except ValueError:
                raise ImportFormatError(path, f"{key!r} is not 'Channel_<number>'", line=i) from None
            names[k] = (value, i)
        else:
            hdr[key] = (value, i)
            if key == "CommentChar" and value:
                comment = value[0]

    def integer(key, low):
        if key not in hdr:
            raise ImportFormatError(path, f"the header has no {key}; expected '{key} <integer>'")
        v, i = hdr[key]
        try:
            n = int(v)
        except ValueError:
            raise ImportFormatError(path, f"{key} is {v[:30]!r}; expected an integer", line=i) from None
        if n < low:
            raise ImportFormatError(path, f"{key} is {n}; expected at least {low}", line=i)
        return n

    n_frames, n_ch = integer("NumFrames", 1), integer("NumChannels", 1)
    n_aux = integer("NumAuxChannels", 0) if "NumAuxChannels" in hdr else 0
    dtype, at = hdr.get("DataType", ("ascii", None))
    if dtype not in ("binary", "ascii"):
        raise ImportFormatError(path, f"DataType is {dtype[:30]!r}; expected 'binary' or 'ascii'", line=at)
    order, at = hdr.get("ByteOrder", ("10", None))
    if order in ("01", "LSB", "LD", "little"):
        endian = "<"
    elif order in ("10", "MSB", "BD", "big"):
        endian = ">"
    else:
        raise ImportFormatError(path, f"ByteOrder is {order[:30]!r}; expected '01' (little-endian) or '10' "
                                "(big-endian)", line=at)
    for k, (_, i) in names.items():
        if k >= n_ch:
            raise ImportFormatError(path, f"Channel_{k} is named but NumChannels is {n_ch}", line=i)
    per_value = 4 if dtype == "binary" else 2  # a float32, or at least a digit and a separator
    if n_frames * (1 + n_ch) * per_value > len(data):  # checked before anything is sized by the header
        raise ImportFormatError(path, f"the header promises NumFrames {n_frames} x NumChannels {n_ch} (at least "
                                f"{n_frames * (1 + n_ch) * per_value} bytes of data) but the file holds "
                                f"{len(data)} bytes; damaged header?")
    channel_names = [names.get(k, (f"channel_{k}", 0))[0] or f"channel_{k}" for k in range(n_ch)]
    return dict(n_frames=n_frames, n_channels=n_ch, n_aux=n_aux, binary=dtype == "binary", endian=endian,
                breaks="BreaksPresent" in hdr, names=channel_names, body=body_start,
                header_lines=text.count("\n") + 1)


def read_est_track(path):
    """The raw contents of an EST Track file.

    Returns
    -------
    times : ndarray of shape (n_frames,) float64, seconds
    values : ndarray of shape (n_frames, n_channels) float64
    valid : ndarray of shape (n_frames,) bool (False where the break value is 0)
    names : list of str, the channel names (``channel_k`` when unnamed)
    """
    data = read_bytes(path)
    h = _parse_est_header(data, path)
    n, c = h["n_frames"], h["n_channels"]
    width = 1 + h["breaks"] + c
    body = data[h["body"]:]
    if h["binary"]:
        need = n * width * 4
        if len(body) < need:
            got = len(body) // (width * 4)
            raise ImportFormatError(
                path, f"the binary data holds {len(body)} bytes, {got} whole frames; the header promises "
                f"NumFrames {n} of {width} float32 values ({need} bytes). Truncated file?", frame=got)
        if len(body) > need:
            raise ImportFormatError(path, f"{len(body) - need} bytes follow the {n} frames the header promises; "
                                    "expected the file to end (wrong NumFrames or NumChannels?)")
        with np.errstate(invalid="ignore", over="ignore"):  # NaN payloads: caught later as non-finite
            arr = np.frombuffer(body, dtype=h["endian"] + "f4", count=n * width).reshape(n, width).astype(np.float64)
    else:
        lines = decode_text(body, path).split("\n")
        first = h["header_lines"] + 1
        rows, lineno = [], []
        extra = h["n_aux"]
        for j, raw in enumerate(lines):
            tok = raw.split()
            if not tok:
                continue
            if len(rows) == n:
                raise ImportFormatError(path, f"more frames than NumFrames {n}", line=first + j)
            if len(tok) != width + extra:
                raise ImportFormatError(path, f"{len(tok)} values; expected {width + extra} (time"
                                        f"{', break' if h['breaks'] else ''}, {c} channels"
                                        f"{f', {extra} aux' if extra else ''})", line=first + j)
            rows.append(parse_floats(tok[:width], path, first + j))
            lineno.append(first + j)
        if len(rows) < n:
            raise ImportFormatError(path, f"{len(rows)} frames; the header promises NumFrames {n}", frame=len(rows))
        arr = np.asarray(rows, dtype=np.float64)
    times = arr[:, 0]
    valid = arr[:, 1] != 0 if h["breaks"] else np.ones(n, dtype=bool)
    return times, arr[:, 1 + h["breaks"]:], valid, h["names"]


# ---------------------------------------------------------------------------- MOCHA ASCII
def _read_mocha_ascii(path):
    lines = decode_text(read_bytes(path), path).split("\n")
    width = 2 + len(MOCHA_CHANNELS)
    rows = []
    for j, raw in enumerate(lines, start=1):
        tok = raw.split()
        if not tok:
            continue
        if len(tok) != width:
            raise ImportFormatError(path, f"{len(tok)} columns; expected {width} (time, valid flag, "
                                    f"{len(MOCHA_CHANNELS)} MOCHA channels) or an EST Track header", line=j)
        rows.append(parse_floats(tok, path, j))
    if not rows:
        raise ImportFormatError(path, "holds no frames; expected lines of 22 numbers (MOCHA ASCII EMA)")
    arr = np.asarray(rows, dtype=np.float64)
    return arr[:, 0], arr[:, 2:], arr[:, 1] != 0, list(MOCHA_CHANNELS)


# ---------------------------------------------------------------------------- corpus
def _sensor_columns(names, path):
    """{sensor: (x column, y column)} from channel names like 'ul_x', 'UL x', 'ulx'."""
    found = {}
    for k, nm in enumerate(names):
        m = _AXIS.match(nm.strip())
        if not m:
            continue
        s = m.group("s").strip("_- .").upper()
        axes = found.setdefault(s, {})
        if m.group("a").lower() in axes:
            j = axes[m.group("a").lower()]
            raise ImportFormatError(path, f"channels {j} ({names[j]!r}) and {k} ({nm!r}) are both sensor {s}'s "
                                    f"{m.group('a').lower()}; expected each channel name once")
        axes[m.group("a").lower()] = k
    pairs = {s: (d["x"], d["y"]) for s, d in found.items() if "x" in d and "y" in d}
    half = {s: d for s, d in found.items() if s not in pairs}
    if pairs:
        return pairs, half
    if len(names) == len(MOCHA_CHANNELS) and not found:  # unnamed channels in MOCHA order
        return _sensor_columns(list(MOCHA_CHANNELS), path)
    raise ImportFormatError(path, f"cannot pair the channels into sensors: names {names[:6]}...; expected names "
                            "ending in x / y (e.g. 'ul_x', 'ul_y') or MOCHA's 20 channels")


@reports_repairs
def read_ema(path, *, sensors=LIP_SENSORS, scale: float = 0.01, rate: float | None = None, alignment=None,
             tier: str | None = None, fill_gaps: bool = True):
    """A MOCHA-TIMIT ``.ema`` file (EST Track binary/ASCII, or ASCII table) as a 2-D corpus.

    Parameters
    ----------
    path : str or Path
    sensors : sequence of str or "all"
        Sensors to keep, in this order (default: upper lip, lower lip, lower incisor = jaw).
    scale : float
        Millimetres per file unit (MOCHA: 1/100 mm, so 0.01).
    rate : float, optional
        Only checked against the rate the frame times give; see :func:`engine.io.resample`.
    alignment : None, False, path or sequence of PhoneInterval
        Phones; by default ``<stem>.lab`` / ``.TextGrid`` beside the file. Fitted to the data
        length (phones past the last frame are cut or dropped).
    tier : str, optional
        TextGrid tier.
    fill_gaps : bool
        Interpolate frames flagged invalid (break value 0) or not finite; else raise.

    Returns
    -------
    Corpus
        One utterance named after the file, ``dims=2``, points named after the sensors,
        frames of shape (n_frames, 2 * n_sensors) in mm, audio ``<stem>.wav`` when present.
    """
    path = Path(path)
    data = read_bytes(path)
    if data.lstrip()[:8] == b"EST_File":
        times, values, valid, names = read_est_track(path)
    else:
        times, values, valid, names = _read_mocha_ascii(path)
    native = check_rate(path, uniform_rate(times, path), rate)
    cols, half = _sensor_columns(names, path)
    want = list(cols) if isinstance(sensors, str) and sensors == "all" else [str(s).upper() for s in sensors]
    for s in (list(half) if isinstance(sensors, str) and sensors == "all" else [s for s in want if s in half]):
        (axis, k), = half[s].items()
        raise ImportFormatError(path, f"sensor {s} has an {axis} channel ({names[k]!r}, channel {k}) but no "
                                f"{'y' if axis == 'x' else 'x'} channel; expected both (a damaged header?)")
    missing = [s for s in want if s not in cols]
    if missing or not want:
        raise ImportFormatError(path, f"no sensor(s) {missing} in the file; it has {sorted(cols)}")
    idx = [c for s in want for c in cols[s]]
    col_names = [f"{s}_{a}" for s in want for a in "xy"]
    frames = _fill_gaps(values[:, idx] * scale, ~valid, path=path, names=col_names, fill=fill_gaps,
                        flagged="break flag 0")
    phones, _ = resolve_alignment(path, alignment, tier=tier)
    return one_utterance_corpus(path, frames, native, dims=2, phones=phones, point_names=want,
                                audio=sidecar_audio(path))
