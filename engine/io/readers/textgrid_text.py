"""Praat's text TextGrid formats (long and short), read as Praat reads them: a stream of values.

Praat writes a TextGrid as numbers, quoted strings and ``<flags>``; the long format puts
``name =`` labels and ``item [1]:`` headings between them, which Praat skips. A string may
span several lines (a label holding a line break, valid in Praat) and holds a double quote
as ``""``. Reading value by value, instead of line by line, keeps both, and keeps every
tier: two tiers of one name are two tiers (a dictionary keyed by name kept only one).
Counts are checked against what follows (Praat reads what a count says and would ignore
the rest): text after the last item is an error naming its line.

Errors are :class:`engine.io.ImportFormatError` naming the file, the line and what was
expected there.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import NamedTuple

from engine.io.errors import ImportFormatError

__all__ = ["TextGridData", "TierData", "Interval", "Point", "parse_textgrid_text"]


class Interval(NamedTuple):
    xmin: float
    xmax: float
    text: str


class Point(NamedTuple):
    xpos: float
    text: str


@dataclass
class TierData:
    """One tier: its Praat class (``"IntervalTier"`` or ``"TextTier"``), name, span and items
    (:class:`Interval` or :class:`Point`, in file order; iterating the tier gives them)."""

    kind: str
    name: str
    xmin: float
    xmax: float
    items: list = field(default_factory=list)
    line: int = 0

    @property
    def is_point_tier(self) -> bool:
        return self.kind != "IntervalTier"

    @property
    def tier_type(self) -> str:
        """``"IntervalTier"`` or ``"PointTier"`` (how the rest of Lipspace names the kinds)."""
        return "PointTier" if self.is_point_tier else "IntervalTier"

    def __iter__(self):
        return iter(self.items)

    def __len__(self):
        return len(self.items)


@dataclass
class TextGridData:
    """A TextGrid's span and its tiers, in file order (names may repeat). Indexing by a name gives
    the tier of that name (KeyError when none, ValueError when two share it)."""

    xmin: float
    xmax: float
    tiers: list

    def names(self) -> list[str]:
        return [t.name for t in self.tiers]

    def __iter__(self):
        return iter(self.names())

    def keys(self) -> list[str]:
        return self.names()

    def items(self) -> list[tuple[str, TierData]]:
        return [(t.name, t) for t in self.tiers]

    def __getitem__(self, name) -> TierData:
        found = [t for t in self.tiers if t.name == name]
        if not found:
            raise KeyError(name)
        if len(found) > 1:
            raise ValueError(f"{len(found)} tiers are named {name!r}")
        return found[0]


_TOKEN = re.compile(r'''
    (?P<str>"(?:[^"]|"")*"?)
  | (?P<flag><[A-Za-z]+>)
  | (?P<brack>\[[^\]\n]*\])
  | (?P<num>[-+]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|(?:nan|inf(?:inity)?)\b))
  | (?P<word>[A-Za-z_][A-Za-z0-9_]*\??)
  | (?P<eq>=)
  | (?P<colon>:)
  | (?P<comment>![^\n]*)
  | (?P<space>\s+)
  | (?P<other>.)
''', re.X | re.I)


def _tokens(text: str, path):
    """(kind, value, line) of every meaningful token; raises on an unterminated string."""
    line = 1
    out = []
    for m in _TOKEN.finditer(text):
        kind, value = m.lastgroup, m.group()
        if kind == "str":
            if len(value) < 2 or not value.endswith('"') or value.count('"') % 2:
                raise ImportFormatError(path, "a quoted label is never closed; expected a closing '\"'", line=line)
            out.append(("str", value[1:-1].replace('""', '"'), line))
        elif kind in ("num", "flag", "word", "eq", "brack", "colon", "other"):
            out.append((kind, value, line))
        line += value.count("\n")
    return out, line if text.endswith("\n") else line + 1  # the line after the last one


class _Reader:
    """A cursor over the tokens that hands out values, skipping the long format's labels."""

    def __init__(self, tokens, end_line, path, lines):
        self.tokens, self.i, self.end_line, self.path, self.lines = tokens, 0, end_line, path, lines

    def _text_at(self, line: int) -> str:
        return self.lines[line - 1].strip()[:60] if 0 < line <= len(self.lines) else ""

    def _fail(self, line, what):
        if line is None:
            raise ImportFormatError(self.path, f"not a valid TextGrid: the file ends; expected {what}",
                                    line=self.end_line)
        raise ImportFormatError(self.path, f"not a valid TextGrid: found {self._text_at(line)!r}; expected {what}",
                                line=line)

    def value(self, kinds, what):
        """The next value of one of ``kinds`` ("num", "str", "flag"); labels before it are skipped, but
        what follows a '=' must be the value itself."""
        after_eq = False
        while self.i < len(self.tokens):
            kind, v, line = self.tokens[self.i]
            self.i += 1
            if kind in ("num", "str", "flag"):
                if kind not in kinds:
                    self._fail(line, what)
                return v, line
            if kind == "other" or after_eq:
                self._fail(line, what)
            after_eq = kind == "eq"
        self._fail(None, what)

    def number(self, what) -> tuple[float, int]:
        v, line = self.value(("num",), what)
        return float(v), line

    def count(self, what) -> tuple[int, int]:
        v, line = self.value(("num",), what)
        try:
            n = int(v)
        except ValueError:
            n = -1
        if n < 0:
            self._fail(line, what)
        return n, line

    def string(self, what) -> tuple[str, int]:
        return self.value(("str",), what)

    def rest(self):
        """The line of the first token left over, or None."""
        return self.tokens[self.i][2] if self.i < len(self.tokens) else None


def parse_textgrid_text(text: str, path) -> TextGridData:
    """A TextGrid in Praat's long or short text format (``text`` already decoded)."""
    lines = text.split("\n")
    tokens, end_line = _tokens(text, path)
    strings = [v for k, v, _ in tokens[:12] if k == "str"]
    if len(strings) < 2 or strings[0] not in ("ooTextFile", "ooTextFile short") or strings[1] != "TextGrid":
        first = next((s.strip() for s in lines if s.strip()), "")
        raise ImportFormatError(path, f"not a Praat TextGrid: the file starts with {first[:60]!r}; expected the "
                                "header lines 'File type = \"ooTextFile\"' and 'Object class = \"TextGrid\"'", line=1)
    r = _Reader(tokens, end_line, path, lines)
    r.string("the header")
    r.string("the header")
    xmin, _ = r.number("the TextGrid's xmin (seconds)")
    xmax, _ = r.number("the TextGrid's xmax (seconds)")
    if r.rest() is None:  # no 'tiers? <exists>': no tiers
        return TextGridData(xmin, xmax, [])
    flag, line = r.value(("flag",), "'tiers? <exists>'")
    if flag.lower() != "<exists>":
        return TextGridData(xmin, xmax, [])
    n_tiers, _ = r.count("'size = <number of tiers>'")
    tiers = []
    for t in range(1, n_tiers + 1):
        kind, line = r.string(f"tier {t}: 'class = \"IntervalTier\"' (or \"TextTier\")")
        if kind not in ("IntervalTier", "TextTier"):
            r._fail(line, f"tier {t}: the class \"IntervalTier\" or \"TextTier\"")
        name, _ = r.string(f"tier {t}: 'name = \"...\"'")
        t_min, _ = r.number(f"tier {t}: 'xmin = <seconds>'")
        t_max, _ = r.number(f"tier {t}: 'xmax = <seconds>'")
        what = "points" if kind == "TextTier" else "intervals"
        n, _ = r.count(f"tier {t}: '{what}: size = <count>'")
        tier = TierData(kind, name, t_min, t_max, [], line)
        for k in range(1, n + 1):
            where = f"tier {t} {'point' if kind == 'TextTier' else 'interval'} {k}"
            if kind == "TextTier":
                time, _ = r.number(f"{where}: 'number = <seconds>'")
                mark, _ = r.string(f"{where}: 'mark = \"...\"'")
                tier.items.append(Point(time, mark))
            else:
                a, line_a = r.number(f"{where}: 'xmin = <seconds>'")
                b, _ = r.number(f"{where}: 'xmax = <seconds>'")
                label, _ = r.string(f"{where}: 'text = \"...\"'")
                if b < a:  # never dropped quietly
                    raise ImportFormatError(path, f"not a valid TextGrid: {where} ({a:g}-{b:g} s) has xmin > xmax; "
                                            "expected an interval that ends after it starts", line=line_a)
                tier.items.append(Interval(a, b, label))
        tiers.append(tier)
    left = r.rest()
    if left is not None:
        raise ImportFormatError(path, f"not a valid TextGrid: found {r._text_at(left)!r} after the last item the "
                                "counts declare; expected "
                                "the end of the file (a tier or interval count, 'size = N', smaller than what the "
                                "file holds?)", line=left)
    return TextGridData(xmin, xmax, tiers)
