"""Phone alignments: Praat TextGrid, HTK / MOCHA ``.lab`` (and ESPS xlabel), TIMIT ``.phn``.

Every reader returns a list of :class:`engine.recordings.corpus.PhoneInterval` (seconds, labels
kept as given) and raises :class:`engine.io.ImportFormatError` naming the file and line.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

from engine.io._util import decode_text, parse_floats, read_bytes
from engine.io.errors import ImportFormatError
from engine.recordings.corpus import PhoneInterval

__all__ = ["read_textgrid", "read_lab", "read_alignment", "resolve_alignment", "textgrid_tiers", "PHONE_TIER_NAMES"]

#: tier names taken as the phone tier, case-insensitive, in order of preference
PHONE_TIER_NAMES = ("phones", "phone", "segments", "phonemes", "phoneme", "segment")

#: largest integer time still read as seconds by ``units="auto"``; larger integers are HTK 100 ns units
HTK_AUTO_THRESHOLD = 1000

_TEXT_HEADER = ['File type = "ooTextFile"', 'Object class = "TextGrid"', ""]


# ---------------------------------------------------------------------------- TextGrid
def _textgrid_bytes(path) -> tuple[bytes, list[str] | None]:
    """Bytes in the form ``textgrids`` parses (UTF-8, modern header) and the stripped lines."""
    data = read_bytes(path)
    if data.startswith(b"ooBinaryFile"):
        return data, None
    text = decode_text(data, path)
    lines = [s.strip() for s in text.split("\n")]
    # Praat's old short format header: 'File type = "ooTextFile short"' then '"TextGrid"'
    if len(lines) >= 2 and lines[0] == 'File type = "ooTextFile short"' and lines[1] == '"TextGrid"':
        lines = _TEXT_HEADER[:2] + lines[2:]
        if len(lines) < 3 or lines[2] != "":
            lines.insert(2, "")
    if lines[:3] != _TEXT_HEADER:
        got = next((s for s in lines[:3] if s), "")
        raise ImportFormatError(
            path, f"not a Praat TextGrid: the file starts with {got[:60]!r}; expected the header lines "
            "'File type = \"ooTextFile\"' and 'Object class = \"TextGrid\"'", line=1)
    return "\n".join(lines).encode("utf-8"), lines


def _locate_textgrid_fault(lines: list[str]) -> tuple[int, str] | None:
    """Walk the text the way ``textgrids`` does and name the first line it cannot use.

    Returns (1-based line number, what was expected) or None if the walk finds no fault.
    """
    body = lines[3:]
    off = 4  # body[i] is line i + off

    def get(i):
        return body[i] if i < len(body) else None

    def need(i, ok, what):
        s = get(i)
        if s is None:
            return (i + off, f"the file ends; expected {what}")
        if not ok(s):
            return (i + off, f"found {s[:60]!r}; expected {what}")
        return None

    def is_num(v):
        try:
            float(v)
            return True
        except ValueError:
            return False

    def is_int(v):
        try:
            return int(v) >= 0
        except ValueError:
            return False

    def val(s):
        parts = s.split(" = ")
        return parts[1] if len(parts) > 1 else None

    def kv(check):
        return lambda s: val(s) is not None and check(val(s))

    def quoted(v):
        return len(v) >= 2 and v[0] == '"' and v[-1] == '"'

    if not body or not body[0]:
        return (off, "the file ends or the line is empty; expected the TextGrid's xmin")
    short = body[0][0] in "-0123456789"
    if not short:
        for i, what in ((0, "'xmin = <seconds>'"), (1, "'xmax = <seconds>'")):
            if (f := need(i, kv(is_num), what)):
                return f
        if get(2) != "tiers? <exists>":
            return None
        if (f := need(3, kv(is_int), "'size = <number of tiers>'")):
            return f
        n_tiers, p = int(val(body[3])), 6
        for t in range(n_tiers):
            if (f := need(p, kv(quoted), f"tier {t + 1}: 'class = \"IntervalTier\"'")) or \
               (f := need(p + 1, kv(quoted), f"tier {t + 1}: 'name = \"...\"'")):
                return f
            point = val(body[p]).strip('"') != "IntervalTier"
            p += 2
            for i, what in ((p, "'xmin = <seconds>'"), (p + 1, "'xmax = <seconds>'"),
                            (p + 2, "'intervals: size = <count>'")):
                if (f := need(i, kv(is_num if i < p + 2 else is_int), f"tier {t + 1}: {what}")):
                    return f
            n, p = int(val(body[p + 2])), p + 4
            for k in range(n):
                fields = (("'number = <seconds>'", is_num), ("'mark = \"...\"'", quoted)) if point else \
                    (("'xmin = <seconds>'", is_num), ("'xmax = <seconds>'", is_num), ("'text = \"...\"'", quoted))
                for j, (what, chk) in enumerate(fields):
                    if (f := need(p + j, kv(chk), f"tier {t + 1} {'point' if point else 'interval'} {k + 1}: {what}")):
                        return f
                p += 3 if point else 4
        return _trailing(body, p - 1 if n_tiers else 4, off)
    for i, what in ((0, "the TextGrid's xmin (seconds)"), (1, "its xmax (seconds)")):
        if (f := need(i, is_num, what)):
            return f
    if get(2) != "<exists>":
        return None
    if (f := need(3, is_int, "the number of tiers")):
        return f
    n_tiers, p = int(body[3]), 4
    for t in range(n_tiers):
        for i, (what, chk) in enumerate((("the tier class in quotes", quoted), ("the tier name in quotes", quoted),
                                         ("tier xmin", is_num), ("tier xmax", is_num),
                                         ("the number of intervals", is_int))):
            if (f := need(p + i, chk, f"tier {t + 1}: {what}")):
                return f
        point = body[p].strip('"') == "PointTier"
        n, p = int(body[p + 4]), p + 5
        for k in range(n):
            fields = (("time", is_num), ("mark in quotes", quoted)) if point else \
                (("xmin", is_num), ("xmax", is_num), ("text in quotes", quoted))
            for j, (what, chk) in enumerate(fields):
                if (f := need(p + j, chk, f"tier {t + 1} item {k + 1}: {what}")):
                    return f
            p += len(fields)
    return _trailing(body, p, off)


def _trailing(body: list[str], p: int, off: int) -> tuple[int, str] | None:
    """A fault when text follows the last item the counts declare (a count smaller than the items)."""
    rest = [i for i in range(max(p, 0), len(body)) if body[i]]
    if not rest:
        return None
    return (rest[0] + off, f"found {body[rest[0]][:60]!r} after the last item the counts declare; expected the end "
            "of the file (a tier or interval count, 'size = N', smaller than what the file holds?)")


def _parse_textgrid(path):
    import textgrids  # praat-textgrids

    data, lines = _textgrid_bytes(path)
    grid = textgrids.TextGrid()
    try:
        grid.parse(data)
    except Exception as exc:  # the library raises TypeError, IndexError, ValueError, struct.error, ...
        fault = _locate_textgrid_fault(lines) if lines is not None else None
        if fault is not None:
            raise ImportFormatError(path, f"not a valid TextGrid: {fault[1]}", line=fault[0]) from None
        kind = "binary" if lines is None else "text"
        raise ImportFormatError(path, f"not a valid {kind} TextGrid ({exc or 'damaged'}); "
                                "expected Praat's long, short or binary TextGrid format") from None
    # the library reads as many items as the counts say and ignores the rest: check the counts
    fault = _locate_textgrid_fault(lines) if lines is not None else None
    if fault is not None:
        raise ImportFormatError(path, f"not a valid TextGrid: {fault[1]}", line=fault[0])
    return grid


def textgrid_tiers(path) -> dict[str, str]:
    """Tier names of a TextGrid and their kind (``"IntervalTier"`` / ``"PointTier"``)."""
    return {name: tier.tier_type for name, tier in _parse_textgrid(path).items()}


def _pick_tier(grid, path, tier):
    names = list(grid.keys())
    if not names:
        raise ImportFormatError(path, "holds no tiers; expected 'tiers? <exists>' and at least one interval tier")
    kinds = ", ".join(f"{n!r} ({grid[n].tier_type})" for n in names)
    if tier is not None:
        if tier in grid:
            return tier
        low = {n.lower(): n for n in names}
        if str(tier).lower() in low:
            return low[str(tier).lower()]
        raise ImportFormatError(path, f"has no tier named {tier!r}; its tiers are {kinds}")
    interval = [n for n in names if not grid[n].is_point_tier]
    for want in PHONE_TIER_NAMES:
        for n in interval:
            # Montreal Forced Aligner names tiers 'speaker - phones'
            if n.strip().lower() == want or n.strip().lower().endswith(" - " + want):
                return n
    if len(interval) == 1:
        return interval[0]
    raise ImportFormatError(
        path, f"cannot tell which tier holds the phones; its tiers are {kinds}. Name one with tier=..., "
        f"or call it one of {', '.join(PHONE_TIER_NAMES)}")


def read_textgrid(path, *, tier: str | None = None) -> list[PhoneInterval]:
    """Phones of a Praat TextGrid (long, short or binary format).

    Parameters
    ----------
    path : str or Path
    tier : str, optional
        Name of the phone tier (case-insensitive). By default the interval tier named
        one of :data:`PHONE_TIER_NAMES` (also ``'<speaker> - phones'``), or the only
        interval tier.

    Returns
    -------
    list of PhoneInterval
        Labelled intervals in time order; empty intervals (unlabelled gaps) are left out.
    """
    grid = _parse_textgrid(path)
    name = _pick_tier(grid, path, tier)
    t = grid[name]
    if t.is_point_tier:
        raise ImportFormatError(path, f"tier {name!r} is a point tier; expected an interval tier of phones")
    out, prev_end = [], -math.inf
    for k, iv in enumerate(t, start=1):
        where = f"tier {name!r} interval {k} ({iv.xmin!r}-{iv.xmax!r})"
        if not (math.isfinite(iv.xmin) and math.isfinite(iv.xmax)):
            raise ImportFormatError(path, f"{where}: times must be finite numbers of seconds")
        if iv.xmin < prev_end - 1e-9:
            raise ImportFormatError(path, f"{where}: starts before the previous interval ends at {prev_end:g} s; "
                                    "expected intervals in time order")
        prev_end = iv.xmax
        label = str(iv.text).strip().replace('""', '"')
        if label and iv.xmax > iv.xmin:
            out.append(PhoneInterval(float(iv.xmin), float(iv.xmax), label))
    return out


# ---------------------------------------------------------------------------- .lab
_INT = re.compile(r"^[+-]?\d+$")


def _xlabel_body(lines):
    """Index of the first data line of an ESPS xlabel file (header ends with a lone '#'), else None."""
    for i, s in enumerate(lines[:40]):
        if s.strip() == "#":
            head = [h for h in lines[:i] if h.strip()]
            if all(h.split()[0] in ("signal", "type", "color", "font", "separator", "nfields", "comment")
                   for h in head):
                return i + 1
    return None


def read_lab(path, *, units: str = "auto", sample_rate: float | None = None) -> list[PhoneInterval]:
    """Phones of a label file: HTK, MOCHA, TIMIT ``.phn`` or ESPS xlabel.

    Lines are ``start end label [anything]`` (``#`` and ``;`` start comments, ``.`` alone
    ends the label list, as in HTK master label files). ESPS xlabel files (a header ending
    with a line holding only ``#``, then ``end_time colour label``) are recognised too.

    Parameters
    ----------
    path : str or Path
    units : {"auto", "seconds", "htk", "samples"}
        Time units. ``"auto"``: when every time is an integer and the largest exceeds
        :data:`HTK_AUTO_THRESHOLD`, HTK's 100 ns units; otherwise seconds. A ``.phn`` file
        defaults to samples at 16 kHz (TIMIT).
    sample_rate : float, optional
        Hz, for ``units="samples"``.

    Returns
    -------
    list of PhoneInterval
    """
    path = Path(path)
    if units not in ("auto", "seconds", "htk", "samples"):
        raise ValueError(f"units={units!r}; expected 'auto', 'seconds', 'htk' or 'samples'")
    lines = decode_text(read_bytes(path), path).split("\n")
    if units == "auto" and path.suffix.lower() == ".phn":
        units, sample_rate = "samples", sample_rate or 16000.0
    if units == "samples" and not (sample_rate and sample_rate > 0):
        raise ValueError(f"units='samples' needs sample_rate (Hz) > 0, got {sample_rate!r}")
    body = _xlabel_body(lines)
    rows: list[tuple[int, float, float, str, bool]] = []  # (line number, start, end, label, all-integer?)
    if body is not None:
        prev = 0.0
        for i in range(body, len(lines)):
            tok = lines[i].split()
            if not tok:
                continue
            if len(tok) < 3:
                raise ImportFormatError(path, f"found {lines[i].strip()[:60]!r}; expected 'end_time colour label' "
                                        "(ESPS xlabel)", line=i + 1)
            (end,) = parse_floats(tok[:1], path, i + 1, "an end time in seconds")
            rows.append((i + 1, prev, end, " ".join(tok[2:]), False))
            prev = end
    else:
        for i, raw in enumerate(lines):
            text = raw.strip()
            if not text or text[0] in "#;\"":  # comments, '#!MLF!#' and MLF file-name lines
                continue
            if text == ".":
                break
            tok = text.split()
            if len(tok) < 3:
                raise ImportFormatError(path, f"found {text[:60]!r} ({len(tok)} field{'s' * (len(tok) != 1)}); "
                                        "expected 'start end label'", line=i + 1)
            start, end = parse_floats(tok[:2], path, i + 1, "a time")
            rows.append((i + 1, start, end, tok[2], bool(_INT.match(tok[0]) and _INT.match(tok[1]))))
    if not rows:
        raise ImportFormatError(path, "holds no labels; expected lines 'start end label'")
    if units == "auto":
        htk = all(r[4] for r in rows) and max(r[2] for r in rows) > HTK_AUTO_THRESHOLD
        scale = 1e-7 if htk else 1.0
    else:
        scale = {"seconds": 1.0, "htk": 1e-7}.get(units) or 1.0 / float(sample_rate or 0)  # checked > 0 above
    out, prev_end = [], -math.inf
    for line, s, e, lab, _ in rows:
        s, e = s * scale, e * scale
        if not (math.isfinite(s) and math.isfinite(e)):
            raise ImportFormatError(path, f"times {s!r} {e!r} of {lab!r} are not finite; expected seconds", line=line)
        if s < 0:
            raise ImportFormatError(path, f"{lab!r} starts at {s:g} s; expected a time >= 0", line=line)
        if e < s:
            raise ImportFormatError(path, f"{lab!r} ends at {e:g} s before it starts at {s:g} s", line=line)
        if s < prev_end - 1e-6:
            raise ImportFormatError(path, f"{lab!r} starts at {s:g} s, before the previous label ends at "
                                    f"{prev_end:g} s; expected labels in time order, not overlapping", line=line)
        prev_end = e
        out.append(PhoneInterval(s, e, lab))
    return out


# ---------------------------------------------------------------------------- dispatch
def read_alignment(path, *, tier: str | None = None, units: str = "auto",
                   sample_rate: float | None = None) -> list[PhoneInterval]:
    """Phones of any supported alignment file, chosen by content (then extension).

    A file starting with Praat's header (text or binary) is a TextGrid; anything else
    is read as a label file (:func:`read_lab`). Zero-length labels are kept here; they
    are dropped when an alignment is fitted to a track.
    """
    data = read_bytes(path)
    head = data[:64].lstrip(b"\xef\xbb\xbf")
    if head.startswith(b"ooBinaryFile") or b"ooTextFile" in head.replace(b"\x00", b"") or \
            Path(path).suffix.lower() == ".textgrid":
        return read_textgrid(path, tier=tier)
    return read_lab(path, units=units, sample_rate=sample_rate)


#: alignment files looked for beside a data file, in order of preference
SIDECAR_SUFFIXES = (".TextGrid", ".textgrid", ".lab", ".phn")


def resolve_alignment(data_path, alignment, *, tier: str | None = None) -> tuple[list[PhoneInterval], str | None]:
    """The phones for a data file.

    Parameters
    ----------
    data_path : path of the data file
    alignment : None, False, path or sequence of PhoneInterval
        None: the first of ``<stem>.TextGrid``, ``<stem>.lab``, ``<stem>.phn`` beside the data
        file, if any; False: no phones; a path: that file; a sequence: used as given.
    tier : str, optional
        TextGrid tier name.

    Returns
    -------
    phones : list of PhoneInterval
    source : str or None
        The alignment file used.
    """
    if alignment is False:
        return [], None
    if alignment is None:
        p = Path(data_path)
        for suf in SIDECAR_SUFFIXES:
            cand = p.with_suffix(suf)
            if cand.is_file() and cand != p:
                return read_alignment(cand, tier=tier), str(cand)
        return [], None
    if isinstance(alignment, (str, Path)):
        return read_alignment(alignment, tier=tier), str(alignment)
    return [p if isinstance(p, PhoneInterval) else PhoneInterval(float(p[0]), float(p[1]), str(p[2]))
            for p in alignment], None
