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

# ---------------------------------------------------------------------------- TextGrid
def _parse_textgrid(path):
    """The TextGrid ``path`` as :class:`engine.io.readers.textgrid_text.TextGridData` (every tier, in order).

    Text TextGrids (long, short; UTF-8 or UTF-16) are read value by value
    (:func:`engine.io.readers.textgrid_text.parse_textgrid_text`: labels spanning lines, double
    quotes, repeated tier names); binary ones by ``praat-textgrids``."""
    from engine.io.readers.textgrid_text import Interval, Point, TextGridData, TierData, parse_textgrid_text

    data = read_bytes(path)
    if not data.startswith(b"ooBinaryFile"):
        return parse_textgrid_text(decode_text(data, path), path)
    import textgrids  # praat-textgrids

    grid = textgrids.TextGrid()
    try:
        grid.parse(data)
    except Exception as exc:  # the library raises TypeError, IndexError, ValueError, struct.error, ...
        raise ImportFormatError(path, f"not a valid binary TextGrid ({exc or 'damaged'}); expected Praat's long, "
                                "short or binary TextGrid format") from None
    tiers = [TierData("TextTier" if t.is_point_tier else "IntervalTier", name, float(grid.xmin), float(grid.xmax),
                      [Point(p.xpos, p.text) for p in t] if t.is_point_tier else
                      [Interval(i.xmin, i.xmax, i.text) for i in t])
             for name, t in grid.items()]
    return TextGridData(float(grid.xmin), float(grid.xmax), tiers)


def textgrid_tiers(path) -> dict[str, str]:
    """Tier names of a TextGrid and their kind (``"IntervalTier"`` / ``"PointTier"``)."""
    return {t.name: t.tier_type for t in _parse_textgrid(path).tiers}


def _pick_tier(grid, path, tier):
    """The name of the phone tier of ``grid`` (``tier`` if given); a name two tiers share is refused."""
    names = grid.names()
    if not names:
        raise ImportFormatError(path, "holds no tiers; expected 'tiers? <exists>' and at least one interval tier")
    kinds = ", ".join(f"{t.name!r} ({t.tier_type})" for t in grid.tiers)
    chosen = None
    if tier is not None:
        if tier in names:
            chosen = tier
        else:
            low = {n.lower(): n for n in names}
            if str(tier).lower() not in low:
                raise ImportFormatError(path, f"has no tier named {tier!r}; its tiers are {kinds}")
            chosen = low[str(tier).lower()]
    else:
        interval = [t.name for t in grid.tiers if not t.is_point_tier]
        for want in PHONE_TIER_NAMES:
            for n in interval:
                # Montreal Forced Aligner names tiers 'speaker - phones'
                if n.strip().lower() == want or n.strip().lower().endswith(" - " + want):
                    chosen = n
                    break
            if chosen is not None:
                break
        if chosen is None and len(interval) == 1:
            chosen = interval[0]
        if chosen is None:
            raise ImportFormatError(
                path, f"cannot tell which tier holds the phones; its tiers are {kinds}. Name one with tier=..., "
                f"or call it one of {', '.join(PHONE_TIER_NAMES)}")
    same = [k + 1 for k, n in enumerate(names) if n == chosen]
    if len(same) > 1:
        raise ImportFormatError(path, f"tiers {' and '.join(map(str, same))} are both named {chosen!r}: which holds "
                                "the phones cannot be told; rename one in Praat (Tier > Rename tier)")
    return chosen


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
    t = next(x for x in grid.tiers if x.name == name)
    if t.is_point_tier:
        raise ImportFormatError(path, f"tier {name!r} is a point tier; expected an interval tier of phones")
    out, prev_end = [], -math.inf
    for k, (a, b, text) in enumerate(t.items, start=1):
        where = f"tier {name!r} interval {k} ({a!r}-{b!r})"
        if not (math.isfinite(a) and math.isfinite(b)):
            raise ImportFormatError(path, f"{where}: times must be finite numbers of seconds")
        if a < prev_end - 1e-9:
            raise ImportFormatError(path, f"{where}: starts before the previous interval ends at {prev_end:g} s; "
                                    "expected intervals in time order")
        prev_end = b
        label = " ".join(str(text).split())  # a label spanning lines (valid in Praat) becomes one line
        if label and b > a:
            if a < -1e-6:  # cut at 0 it would lose part of the phone, and its times would not be the data's
                raise ImportFormatError(path, f"{where}: {label!r} starts at {a:g} s, before the recording starts "
                                        "(0 s); expected a tier starting at 0 (Praat: Modify times > Shift times to)")
            out.append(PhoneInterval(float(a), float(b), label))
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


def _same(a: Path, b: Path) -> bool:
    """Whether two names are one file (``x.TextGrid`` and ``x.textgrid`` on a case-insensitive disk)."""
    try:
        return a.samefile(b)
    except OSError:
        return False


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
        found: list[Path] = []
        for suf in SIDECAR_SUFFIXES:
            cand = p.with_suffix(suf)
            if cand.is_file() and cand != p and not any(_same(cand, f) for f in found):
                found.append(cand)
        if not found:
            return [], None
        if len(found) > 1:  # one is used, and which is said
            from engine.io.repairs import report_repair

            report_repair(p, f"{' and '.join(f.name for f in found)} are beside it: the phones are read from "
                          f"{found[0].name} (give the other with --alignment)")
        return read_alignment(found[0], tier=tier), str(found[0])
    if isinstance(alignment, (str, Path)):
        return read_alignment(alignment, tier=tier), str(alignment)
    return [p if isinstance(p, PhoneInterval) else PhoneInterval(float(p[0]), float(p[1]), str(p[2]))
            for p in alignment], None
