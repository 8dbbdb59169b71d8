"""Who spoke each input file: speaker rules, and checks that a rule fits the file names.

A corpus of many recordings names its speakers in the file names or the folders
(``F01_B01_S01.mat``, ``S2/utt03.csv``, ``ABCFIA01.mat`` ... ``XYMNE16.mat``). A
:class:`SpeakerRule` turns an input path into a speaker name:

==============  ====================================================================
``dir``         the name of the folder holding the file, as the path was given (a
                symlinked folder gives its own name, not its target's);
``prefix``      the file name up to the first ``_``;
``re:PATTERN``  the one group of a regular expression searched in the file name,
                e.g. ``re:^(spk[0-9]+)`` or ``re:^([A-Z]{3})`` for ``ABCFIA01.mat``.
==============  ====================================================================

A rule that does not fit the names gives a corpus whose speaker normalisation is wrong
without any error: every file its own speaker (each utterance normalised on its own), one
speaker for recordings whose names say they are several people, or a speaker code fused
with a condition code (``XYZFIA``: speaker, sex and emotion). :func:`check_assignment`
finds all three from the names' scheme (:mod:`engine.recordings.file_names`) and says
what to do and what the pattern it proposes would give; ``lipspace import`` prints its
sentences as warnings. :func:`suggest_fields` is the note that proposes a
``--fields-from`` pattern keeping every part of the names as a field.
"""
from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

from engine.recordings.corpus import CorpusWarning

__all__ = ["SpeakerRule", "SpeakerRuleError", "SpeakerWarning", "check_assignment", "name_groups", "leading_letters",
           "structure_hint", "suggest_fields"]


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
        assert self.pattern is not None  # a 're:' rule
        m = self.pattern.search(p.name)
        if m is None or not m.group(1):
            raise SpeakerRuleError(f"{p}: the file name {p.name!r} does not match the speaker rule "
                                   f"{self.spec!r}; expected a match whose group names the speaker")
        return m.group(1)


_LEADING = re.compile(r"^[^\W\d_]*")


def leading_letters(stem: str) -> str:
    """The letters a file name starts with (``ABCFIA01`` -> ``ABCFIA``, ``F01_B01`` -> ``F``)."""
    m = _LEADING.match(stem)
    return m.group(0) if m else ""  # the pattern matches every string (perhaps empty)


def name_groups(paths) -> dict[str, int]:
    """Files per leading letters of their names, in first-seen order (``{"ABCFIA": 16, "XYMNE": 16}``)."""
    out: dict[str, int] = {}
    for p in paths:
        key = leading_letters(Path(str(p)).stem)
        out[key] = out.get(key, 0) + 1
    return out


def _grouping_hint(paths) -> tuple[dict, str]:
    """(groups, hint): the leading-letter groups when they look like speakers, else ({}, "").

    Used for names that share no scheme :func:`engine.recordings.file_names.name_structure` can read."""
    groups = name_groups(paths)
    n = len(paths)
    if not 2 <= len(groups) <= max(2, n // 2):
        return {}, ""
    shown = ", ".join(f"{k or '(none)'} {v}" for k, v in list(groups.items())[:6])
    more = " ..." if len(groups) > 6 else ""
    return groups, (f"their names start with {len(groups)} different letter codes ({shown}{more} files); if these "
                    "are the speakers, name them with --speaker-from 're:^([A-Za-z]+)'")


def structure_hint(structure) -> str:
    """What the names' scheme says about speakers, with the option that names them and what it would give ("" when
    the scheme has no plausible speakers)."""
    if structure is None or not structure.plausible_speakers():
        return ""
    spk = structure.speakers
    if all(leading_letters(s) == v for s, v in zip(structure.stems, dict(structure.fields)["speaker"])):
        shown = ", ".join(f"{k} {v}" for k, v in list(spk.items())[:6]) + (" ..." if len(spk) > 6 else "")
        return (f"their names start with {len(spk)} different letter codes ({shown} files); if these are the "
                f"speakers, name them with --speaker-from 're:^([A-Za-z]+)', or keep every part of the name as a "
                f"field with --fields-from 're:{structure.pattern}', which would give {structure.describe()}")
    others = [name for name, _ in structure.fields[1:]]
    shape = " x ".join([f"{len(spk)} speakers"] + [f"{len(structure.levels(o))} {o} levels" for o in others])
    return (f"their names look like {shape}: --fields-from 're:{structure.pattern}' would give {structure.describe()}")


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
        Empty when nothing looks wrong. The names' scheme
        (:func:`engine.recordings.file_names.name_structure`) decides what is plausible; three
        cases are reported: with a rule, three or more inputs each becoming its own speaker
        (the build would normalise every recording on its own); every input getting the
        same speaker (or none; not an explicit single name) while the scheme names two or
        more speakers, at most half as many as files (recordings of several people pooled as
        one); a rule giving more speakers than the scheme, each of its speakers inside one
        of the scheme's (a speaker code fused with a condition crossed with it). Every
        suggestion says what it would give on these names.
    """
    from engine.recordings.file_names import name_structure

    paths = [str(p) for p in paths]
    speakers = [str(s) for s in speakers]
    n = len(paths)
    if n != len(speakers):
        raise ValueError(f"{n} paths but {len(speakers)} speakers; expected one speaker per input")
    structure = name_structure(paths)
    hint = structure_hint(structure) if structure is not None else _grouping_hint(paths)[1]
    out = []
    distinct = list(dict.fromkeys(speakers))
    if rule is not None and n >= 3 and len(distinct) == n:
        why = " (the names have no '_')" if rule == "prefix" and not any("_" in Path(p).stem for p in paths) else ""
        out.append(f"--speaker-from {rule} made each of the {n} inputs its own speaker{why}: "
                   f"{', '.join(distinct[:4])}{' ...' if n > 4 else ''}; the build would normalise every recording "
                   "on its own, removing its movement along with the speaker. "
                   + (hint[0].upper() + hint[1:] if hint else
                      "Give a rule that names the speakers, e.g. --speaker-from 're:^([A-Za-z]+)' or "
                      "--speaker-from dir"))
    elif n >= 2 and len(distinct) == 1 and (rule is not None or not distinct[0]):  # --speaker NAME: as told
        if hint:
            who = (f"speaker {distinct[0]!r} (--speaker-from {rule})" if distinct[0] else
                   "one unnamed speaker (no --speaker or --speaker-from)")
            out.append(f"all {n} inputs are {who}, but {hint}, or give --speaker NAME if they are one person")
    elif rule is not None and structure is not None and structure.plausible_speakers():
        spk = dict(structure.fields)["speaker"]
        theirs: dict[str, Any] = {}
        for mine, s in zip(speakers, spk):
            theirs.setdefault(mine, set()).add(s)
        if len(distinct) > len(set(spk)) and all(len(v) == 1 for v in theirs.values()):
            out.append(f"--speaker-from {rule} gave {len(distinct)} speakers ({', '.join(distinct[:6])}"
                       f"{' ...' if len(distinct) > 6 else ''}), but {hint}; each of those {len(distinct)} "
                       "'speakers' is one speaker in one condition, and the build would normalise every "
                       "condition away with the speaker")
    return out


def suggest_fields(paths) -> str:
    """A note for an import that names no fields: the names' scheme and the ``--fields-from`` pattern that would
    keep its parts, with what it would give ("" when the names share no scheme, or none of its parts other than
    the speaker repeats like a condition)."""
    from engine.recordings.file_names import name_structure

    st = name_structure(paths)
    n = len(paths)
    # only a scheme with a condition-like part (2 or more levels, each of 2 or more files on average) is worth
    # keeping as fields; a number unique to each file is an id, not a condition
    if st is None or not any(2 <= len(st.levels(k)) <= n // 2 for k, _ in st.fields[1:]):
        return ""
    return (f"the file names follow one scheme; --fields-from 're:{st.pattern}' would keep its parts as fields: "
            f"{st.describe()} (rename the groups as you like; lipspace info, table and evaluate --by use them)")
