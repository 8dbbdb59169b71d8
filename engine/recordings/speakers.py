"""Who spoke each input file: speaker rules, and checks that a rule fits the file names.

A corpus of many recordings names its speakers in the file names or the folders
(``F01_B01_S01.mat``, ``S2/utt03.csv``, ``ABCFIA01.mat`` ... ``XYMNE16.mat``). A
:class:`SpeakerRule` turns an input path into a speaker name:

``dir``         the name of the folder holding the file, as the path was given (a
                symlinked folder gives its own name, not its target's);
``prefix``      the file name up to the first ``_``;
``re:PATTERN``  the one group of a regular expression searched in the file name,
                e.g. ``re:^(spk[0-9]+)`` or ``re:^([A-Z]{3})`` for ``ABCFIA01.mat``.

A rule that does not fit the names gives a corpus whose speaker normalisation is wrong
without any error: every file its own speaker (each utterance normalised on its own), or
one speaker for recordings whose names say they are several people.
:func:`check_assignment` finds both and says what to do; ``lipspace import`` prints
its sentences as warnings.
"""
from __future__ import annotations

import os
import re
from pathlib import Path

from engine.recordings.corpus import CorpusWarning

__all__ = ["SpeakerRule", "SpeakerRuleError", "SpeakerWarning", "check_assignment", "name_groups", "leading_letters"]


class SpeakerRuleError(ValueError):
    """A speaker rule that cannot be used (unknown, bad regular expression, no match)."""


class SpeakerWarning(CorpusWarning):
    """The speakers an import assigned look wrong for the file names."""


class SpeakerRule:
    """A rule from an input path to its speaker (see the module docstring).

    Parameters
    ----------
    spec : str
        ``"dir"``, ``"prefix"`` or ``"re:PATTERN"`` (exactly one group).

    Raises
    ------
    SpeakerRuleError
        An unknown rule, a pattern that does not compile or does not have one group.
    """

    def __init__(self, spec: str):
        spec = str(spec)
        self.spec = spec
        self.pattern = None
        if spec in ("dir", "prefix"):
            return
        if not spec.startswith("re:"):
            raise SpeakerRuleError(f"speaker rule {spec!r}: expected 'dir', 'prefix' or 're:PATTERN' (a regular "
                                   "expression with one group, e.g. 're:^(spk[0-9]+)')")
        try:
            self.pattern = re.compile(spec[3:])
        except re.error as exc:
            raise SpeakerRuleError(f"speaker rule {spec!r}: not a regular expression ({exc})") from None
        if self.pattern.groups != 1:
            raise SpeakerRuleError(f"speaker rule {spec!r} has {self.pattern.groups} groups; expected exactly one "
                                   "group in parentheses around the speaker's part of the file name, "
                                   "e.g. 're:^([A-Z]{3})'")

    def __repr__(self):
        return f"SpeakerRule({self.spec!r})"

    def __call__(self, path) -> str:
        """The speaker of ``path``.

        Raises
        ------
        SpeakerRuleError
            ``re:`` finds no match (or an empty group) in the file name, or ``dir`` has no
            folder name to give.
        """
        p = Path(str(path))
        if self.spec == "dir":
            # the path as given, made absolute without following symlinks
            name = Path(os.path.abspath(str(p))).parent.name
            if not name:
                raise SpeakerRuleError(f"{p}: lies in the file system's root; 'dir' has no folder name to give")
            return name
        if self.spec == "prefix":
            return p.stem.split("_", 1)[0]
        m = self.pattern.search(p.name)
        if m is None or not m.group(1):
            raise SpeakerRuleError(f"{p}: the file name {p.name!r} does not match the speaker rule "
                                   f"{self.spec!r}; expected a match whose group names the speaker")
        return m.group(1)


_LEADING = re.compile(r"^[^\W\d_]*")


def leading_letters(stem: str) -> str:
    """The letters a file name starts with (``ABCFIA01`` -> ``ABCFIA``, ``F01_B01`` -> ``F``)."""
    return _LEADING.match(stem).group(0)


def name_groups(paths) -> dict[str, int]:
    """Files per leading letters of their names, in first-seen order (``{"ABCFIA": 16, "XYMNE": 16}``)."""
    out: dict[str, int] = {}
    for p in paths:
        key = leading_letters(Path(str(p)).stem)
        out[key] = out.get(key, 0) + 1
    return out


def _grouping_hint(paths) -> tuple[dict, str]:
    """(groups, hint): the leading-letter groups when they look like speakers, else ({}, "")."""
    groups = name_groups(paths)
    n = len(paths)
    if not 2 <= len(groups) <= max(2, n // 2):
        return {}, ""
    shown = ", ".join(f"{k or '(none)'} {v}" for k, v in list(groups.items())[:6])
    more = " ..." if len(groups) > 6 else ""
    return groups, (f"their names start with {len(groups)} different letter codes ({shown}{more} files); if these "
                    "are the speakers, name them with --speaker-from 're:^([A-Za-z]+)'")


def check_assignment(paths, speakers, *, rule: str | None) -> list[str]:
    """Sentences warning that a speaker assignment looks wrong for the file names.

    Parameters
    ----------
    paths : sequence of str or Path
        The inputs, one per file (or folder) read.
    speakers : sequence of str
        The speaker each input got ("" = none).
    rule : str or None
        The rule that named them (``--speaker-from``), or None when none was given.

    Returns
    -------
    list of str
        Empty when nothing looks wrong. Two cases are reported: with a rule, three or more
        inputs each becoming its own speaker (the build would normalise every recording on
        its own); with a rule or none (not an explicit single name), every input getting the
        same speaker (or none) while the file names start with 2 or more letter codes, as many as half the files
        at most (recordings of several people pooled as one).
    """
    paths = [str(p) for p in paths]
    speakers = [str(s) for s in speakers]
    n = len(paths)
    if n != len(speakers):
        raise ValueError(f"{n} paths but {len(speakers)} speakers; expected one speaker per input")
    out = []
    distinct = list(dict.fromkeys(speakers))
    if rule is not None and n >= 3 and len(distinct) == n:
        _, hint = _grouping_hint(paths)
        why = " (the names have no '_')" if rule == "prefix" and not any("_" in Path(p).stem for p in paths) else ""
        out.append(f"--speaker-from {rule} made each of the {n} inputs its own speaker{why}: "
                   f"{', '.join(distinct[:4])}{' ...' if n > 4 else ''}; the build would normalise every recording "
                   "on its own, removing its movement along with the speaker. "
                   + (hint[0].upper() + hint[1:] if hint else
                      "Give a rule that names the speakers, e.g. --speaker-from 're:^([A-Za-z]+)' or "
                      "--speaker-from dir"))
    elif n >= 2 and len(distinct) == 1 and (rule is not None or not distinct[0]):  # --speaker NAME: as told
        groups, hint = _grouping_hint(paths)
        if groups:
            who = (f"speaker {distinct[0]!r} (--speaker-from {rule})" if distinct[0] else
                   "one unnamed speaker (no --speaker or --speaker-from)")
            out.append(f"all {n} inputs are {who}, but {hint}, or give --speaker NAME if they are one person")
    return out
