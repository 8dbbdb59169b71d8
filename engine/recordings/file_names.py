"""The structure of a lab's file names: which parts name the speaker, which a condition or an item.

Labs name recordings by a scheme: ``F01_B01_S01_R01_N.mat`` (speaker, block, sentence,
repetition, rate), ``XYZFIA01.mat`` (speaker ``XYZ``, sex ``F``, emotion ``IA``, text ``01``).
:func:`name_structure` reads such a scheme off the names themselves, so that what the
program suggests is right on the names it has seen:

1. Names with separators (``_``, ``-``, ``.``, spaces) in the same places are split there;
   names without are split into runs of letters and of digits (``XYZFIA`` | ``01``),
   and every name must give the same sequence of kinds. Names that do not share one
   scheme get no structure (and no suggestion).
2. A part that takes one value in every name is constant. A run of letters taking
   several values is split when a fixed-width ending of it varies *across* its beginning:
   either the beginning is the same in every name (``XYZF`` + ``IA``, ``XYZF`` + ``NE``: one
   speaker, a two-letter condition), or beginning and ending are crossed, most of the
   combinations of their values occurring (``XYZF``/``ABCM``/``DEFF`` x ``IA``/``NE``/...:
   three speakers, each in every condition). A fused code (``XYZFIA``) is therefore
   never taken for a speaker when the names show it is a speaker and a condition.
3. The first part of the name is the speaker; varying letter parts after it are
   conditions, digit parts items.

:class:`NameStructure` gives the pattern with named groups (for ``--fields-from``), the
levels each field would take, and a sentence saying so.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

__all__ = ["NameStructure", "name_structure", "crossed_split", "SEPARATORS"]

#: characters that separate the parts of a file name
SEPARATORS = "_-. "
_RUNS = re.compile(r"[A-Za-z]+|[0-9]+")
#: a split is crossed when the combinations seen are at least this share of all combinations
CROSSED_SHARE = 0.8


@dataclass(frozen=True)
class NameStructure:
    """A file-name scheme read off the names.

    Attributes
    ----------
    pattern : str
        Regular expression with a named group per field (``--fields-from 're:' + pattern``).
    fields : tuple of (str, tuple of str)
        ``(name, value per file)`` in name order; the first is ``speaker``.
    stems : tuple of str
        The names it was read from.
    """

    pattern: str
    fields: tuple
    stems: tuple

    def levels(self, name: str) -> dict[str, int]:
        """``{level: n files}`` of field ``name``, in first-seen order."""
        values = dict(self.fields)[name]
        out: dict[str, int] = {}
        for v in values:
            out[v] = out.get(v, 0) + 1
        return out

    @property
    def speakers(self) -> dict[str, int]:
        return self.levels("speaker")

    def plausible_speakers(self) -> bool:
        """Whether the speaker field could name speakers: 2 or more of them, and on average at least two files
        each (two files of two speakers, as a sample pair, also count)."""
        k, n = len(self.speakers), len(self.stems)
        return 2 <= k <= max(2, n // 2)

    def describe(self, limit: int = 6) -> str:
        """What the pattern would give: ``speaker 3 levels (XYZF 112, ABCM 105, DEFF 108 files); ...``."""
        parts = []
        for name, _ in self.fields:
            lv = self.levels(name)
            shown = ", ".join(f"{k} {v}" for k, v in list(lv.items())[:limit])
            more = " ..." if len(lv) > limit else ""
            crossed = (", with every speaker" if name != "speaker" and len(self.speakers) > 1 and len(lv) > 1
                       and self.crossed_with_speaker(name) else "")
            parts.append(f"{name} {len(lv)} level{'s' * (len(lv) != 1)} ({shown}{more} files{crossed})")
        return "; ".join(parts)

    def crossed_with_speaker(self, name: str) -> bool:
        """Whether field ``name`` is crossed with the speaker (most speaker x level combinations occur)."""
        s, f = dict(self.fields)["speaker"], dict(self.fields)[name]
        combos = len(set(zip(s, f)))
        return combos >= CROSSED_SHARE * len(set(s)) * len(set(f))


def _kind(token: str) -> str:
    return "L" if token.isalpha() else "D" if token.isdigit() else "M"


def _split_parts(stems):
    """Every stem as parts ``[(text, kind)]`` with the separators between them, or None when the stems do not
    share one scheme."""
    seps = [re.findall(f"[{re.escape(SEPARATORS)}]+", s) for s in stems]
    if seps[0] and all(x == seps[0] for x in seps):
        split = [re.split(f"[{re.escape(SEPARATORS)}]+", s) for s in stems]
        if all(len(p) == len(split[0]) for p in split) and all(all(x for x in p) for p in split):
            return [[(x, "S") for x in p] for p in split], seps[0]
        return None
    if any(seps):
        return None
    runs = [_RUNS.findall(s) for s in stems]
    if any("".join(r) != s for r, s in zip(runs, stems)):
        return None  # other characters: no scheme read here
    kinds = [tuple(_kind(t) for t in r) for r in runs]
    if any(k != kinds[0] for k in kinds):
        return None
    return [[(t, _kind(t)) for t in r] for r in runs], None


def crossed_split(values) -> tuple[int, str] | None:
    """The fixed-width ending ``w`` at which letter codes ``values`` (one per file) split into a beginning and an
    ending that vary independently: ``(w, "common")`` when every code starts with the same letters and has the
    same length (the ending is what follows them), ``(w, "crossed")`` when beginning and ending both take
    several values and at least :data:`CROSSED_SHARE` of their combinations occur (the best-covered, then the
    narrowest, width); None when neither holds."""
    import os

    values = list(values)
    if len(set(values)) < 2:
        return None
    common = len(os.path.commonprefix(values))
    if common and len({len(v) for v in values}) == 1:
        return len(values[0]) - common, "common"
    best = None
    for w in range(1, min(len(v) for v in values)):
        pre, suf = [v[:-w] for v in values], [v[-w:] for v in values]
        P, S = set(pre), set(suf)
        if len(P) < 2 or len(S) < 2:
            continue
        share = len(set(zip(pre, suf))) / (len(P) * len(S))
        if share >= CROSSED_SHARE and (best is None or share > best[1]):
            best = (w, share)
    return None if best is None else (best[0], "crossed")


def name_structure(paths) -> NameStructure | None:
    """The scheme of the file names of ``paths`` (module docstring), or None when they share none or are fewer
    than two."""
    stems = [Path(str(p)).stem for p in paths]
    if len(stems) < 2:
        return None
    split = _split_parts(stems)
    if split is None:
        return None
    parts, seps = split
    n_parts = len(parts[0])
    cols = []  # (regex, values or None for constant, kind)
    for j in range(n_parts):
        vals = [p[j][0] for p in parts]
        kind = parts[0][j][1]
        any_of = {"L": "[A-Za-z]+", "D": "[0-9]+"}.get(kind, f"[^{re.escape(SEPARATORS)}]+")
        if kind == "L" and len(set(vals)) > 1:
            cut = crossed_split(vals)
            if cut is not None:
                w, how = cut
                cols.append((any_of, [v[:-w] for v in vals], "L", how == "common"))
                cols.append((f"[A-Za-z]{{{w}}}", [v[-w:] for v in vals], "L", False))
                continue
        cols.append((any_of, vals, kind, len(set(vals)) == 1))
    names: list[str]
    out: list[tuple[str, tuple[str, ...]]]
    regex: list[str]
    names, out, regex = [], [], []
    for j, (rx, vals, kind, constant) in enumerate(cols):
        first = j == 0
        if constant and not first:
            regex.append(rx)
        else:
            base = "speaker" if first else {"L": "condition", "D": "item"}.get(kind, "part")
            name = base if base not in names else f"{base}{sum(n.startswith(base) for n in names) + 1}"
            names.append(name)
            out.append((name, tuple(vals)))
            regex.append(f"(?P<{name}>{rx})")
        if seps is not None and j < len(seps):
            regex.append(re.escape(seps[j]))
    return NameStructure("^" + "".join(regex) + "$", tuple(out), tuple(stems))
