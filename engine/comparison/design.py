"""The design of a comparison: which utterances are compared, what is exchangeable, what can be tested.

Frames of one utterance are not independent, so the unit a comparison resamples is never a
frame: it is the utterance, or the speaker when the compared field is a property of
speakers. :func:`resolve_design` reads the design off the levels, the speakers and an
optional pairing field:

``within blocks`` (paired)
    ``paired_by`` given (e.g. ``text``: the same sentence said in each emotion): the labels
    are permuted among the utterances of each block, a block being one value of the pairing
    field (and one speaker, when the compared field varies within speakers). Blocks holding
    only one of the two levels are left out; the bootstrap resamples whole blocks.
``within speaker``
    No pairing field, several speakers, and the field varies within some of them: labels
    are permuted within each speaker (speakers holding one level only are left out), so a
    difference between speakers cannot pass for a difference between the levels.
``between speakers``
    Several speakers, each holding one level only (sex, group, patient/control): whole
    speakers are the unit; their labels are permuted and the bootstrap resamples speakers.
``between utterances``
    One speaker, unknown speakers, or the field *is* the speaker (the speakers are compared as
    individuals): utterance labels are permuted freely.

The labels of ``n`` units of which ``m`` carry the second level can be arranged in
``C(n, m)`` ways (per stratum, multiplied). When that number is below ``1 / alpha`` no
p-value can reach ``alpha``: the design is not testable, and says why.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from engine.comparison.fields import FieldError, level_counts

__all__ = ["ComparisonError", "Design", "resolve_design", "KINDS", "UNKNOWN_SPEAKER"]

#: the designs, in the words every result states
KINDS = ("between utterances", "within blocks", "within speaker", "between speakers")
#: the name an utterance with no speaker takes when other utterances name theirs
UNKNOWN_SPEAKER = "(unknown speaker)"


class ComparisonError(FieldError):
    """A comparison the data cannot support (one level, levels that never share a block, ...)."""


@dataclass(frozen=True)
class Design:
    """Who is compared with whom, what is resampled, and whether a test is possible.

    Attributes
    ----------
    by, level_a, level_b : str
        The field and its two levels (the estimate is level_b against level_a).
    paired_by : str
        The pairing field ("" = none).
    kind : str
        One of :data:`KINDS`.
    utterances : ndarray of shape (U,), int64
        The utterances compared (indices into the corpus's utterances).
    group : ndarray of shape (U,), int8
        0 for level_a, 1 for level_b.
    speakers : ndarray of shape (U,), str
    unit : ndarray of shape (U,), int64
        The resampling unit of each utterance (an utterance, or its speaker).
    unit_group, unit_stratum : ndarray of shape (n_units,), int64
        Each unit's level and the stratum its label is permuted within.
    stratum_names : tuple of str
    bootstrap : {"cells", "blocks"}
        Units resampled within each (stratum, level) cell, or whole strata (paired designs).
    n_arrangements : int
        Distinct arrangements of the labels the permutation can make.
    testable : bool
        ``1 / n_arrangements <= alpha``.
    can_bootstrap : bool
        Every resampled cell holds at least two units (else no interval).
    reason : str
        Why nothing can be tested ("" when testable).
    notes : tuple of str
        What was left out and what the design means.
    alpha : float
    """

    by: str
    level_a: str
    level_b: str
    paired_by: str
    kind: str
    utterances: np.ndarray
    group: np.ndarray
    speakers: np.ndarray
    unit: np.ndarray
    unit_group: np.ndarray
    unit_stratum: np.ndarray
    stratum_names: tuple
    bootstrap: str
    n_arrangements: int
    testable: bool
    can_bootstrap: bool
    reason: str
    notes: tuple
    alpha: float

    @property
    def unit_name(self) -> str:
        return "speaker" if self.kind == "between speakers" else "utterance"

    @property
    def n_units(self) -> tuple[int, int]:
        """Units of level_a and level_b."""
        return int((self.unit_group == 0).sum()), int((self.unit_group == 1).sum())

    @property
    def n_strata(self) -> int:
        return len(self.stratum_names)

    def describe(self) -> str:
        """One line: the design as every result row states it."""
        na, nb = self.n_units
        u = self.unit_name
        what = {"between utterances": f"{u}s exchangeable",
                "within blocks": f"labels permuted within {self.n_strata} {self._blocks_word()}",
                "within speaker": f"labels permuted within each of {self.n_strata} speaker"
                                  f"{'s' if self.n_strata != 1 else ''}",
                "between speakers": "whole speakers exchangeable"}[self.kind]
        head = f"{self.kind}: {self.level_a} {na} vs {self.level_b} {nb} {u}s; {what}"
        return head if self.testable else f"{head}; descriptive only ({self.reason_short()})"

    def _blocks_word(self) -> str:
        word = "block" if self.n_strata == 1 else "blocks"
        return f"{self.paired_by} {word}" if self.paired_by else word

    def reason_short(self) -> str:
        if self.testable:
            return ""
        return f"cannot test: {self.n_arrangements} arrangements, smallest p {1.0 / self.n_arrangements:.2g}"


def _arrangements(unit_group, unit_stratum, n_strata) -> int:
    total = 1
    for s in range(n_strata):
        g = unit_group[unit_stratum == s]
        total *= math.comb(len(g), int(g.sum()))
    return int(total)


def _speaker_levels(speakers, group) -> dict:
    out: dict[str, set] = {}
    for s, g in zip(speakers, group):
        out.setdefault(str(s), set()).add(int(g))
    return out


def resolve_design(values, level_a: str, level_b: str, *, by: str = "level", speakers=None, pairs=None,
                   paired_by: str = "", alpha: float = 0.05) -> Design:
    """The design comparing ``level_b`` with ``level_a`` of one field (module docstring).

    Parameters
    ----------
    values : sequence of str, length n_utterances
        The compared field's level of each utterance ("" unknown: left out).
    level_a, level_b : str
    by : str
        The field's name (for messages; ``"speaker"`` compares speakers as individuals).
    speakers : sequence of str or None
        Each utterance's speaker ("" unknown).
    pairs : sequence of str or None
        Each utterance's value of the pairing field (required with ``paired_by``).
    paired_by : str
        Name of the pairing field ("" = unpaired).
    alpha : float
        The level a p-value must be able to reach for a test to be run.

    Returns
    -------
    Design

    Raises
    ------
    ComparisonError
        A level absent, the same level twice, or (paired) no block holding both levels.
    """
    values = np.asarray(values, dtype=str)
    n = len(values)
    if not 0 < alpha < 1:
        raise ValueError(f"alpha={alpha!r}: must be between 0 and 1 (e.g. 0.05)")
    counts = level_counts(values)
    have = ", ".join(f"{k} ({v})" for k, v in counts.items()) or "none"
    if level_a == level_b:
        raise ComparisonError(f"field {by!r}: level {level_a!r} given twice; compare two different levels "
                              f"(levels and their utterances: {have})")
    for lv in (level_a, level_b):
        if lv not in counts:
            raise ComparisonError(f"field {by!r} has no level {lv!r}; its levels (utterances): {have}")
    speakers = np.full(n, "", dtype=object) if speakers is None else np.asarray(speakers, dtype=object)
    if len(speakers) != n:
        raise ValueError(f"speakers has {len(speakers)} values for {n} utterances; give one per utterance")
    notes = []
    sel = np.flatnonzero((values == level_a) | (values == level_b))
    group = (values[sel] == level_b).astype(np.int8)
    spk = np.asarray([str(s) for s in speakers[sel]], dtype=object)
    if (spk == "").any() and (spk != "").any():
        notes.append(f"{int((spk == '').sum())} utterance(s) name no speaker: counted as one speaker "
                     f"{UNKNOWN_SPEAKER!r}")
        spk[spk == ""] = UNKNOWN_SPEAKER
    n_spk = len(set(spk) - {""})
    by_speaker = _speaker_levels(spk, group)
    varies_within = any(len(v) == 2 for v in by_speaker.values())
    is_speaker_field = by == "speaker"

    if is_speaker_field and n_spk >= 2:
        notes.append("the speakers are compared as individuals: the result is about these speakers' "
                     "utterances, not about any population of speakers")
    if paired_by:
        if pairs is None:
            raise ValueError("paired_by given without the pairing field's values (pairs=)")
        pv = np.asarray([str(p) for p in np.asarray(pairs, dtype=object)[sel]], dtype=object)
        combine = not is_speaker_field and paired_by != "speaker" and n_spk >= 2 and varies_within
        keys = np.asarray([f"{p}\x1f{s}" if combine else p for p, s in zip(pv, spk)], dtype=object)
        known = pv != ""
        if (~known).any():
            notes.append(f"{int((~known).sum())} utterance(s) with no {paired_by} value left out")
        both = {k for k in set(keys[known]) if len(set(group[(keys == k) & known])) == 2}
        if not both:
            a_vals = sorted(set(pv[(group == 0) & known]))[:5]
            b_vals = sorted(set(pv[(group == 1) & known]))[:5]
            within = " by the same speaker" if combine else ""
            raise ComparisonError(
                f"levels {level_a!r} and {level_b!r} of {by!r} never share a {paired_by}{within}: no {paired_by} "
                f"value has utterances of both (e.g. {level_a}: {', '.join(a_vals) or 'none'}; {level_b}: "
                f"{', '.join(b_vals) or 'none'}). A comparison paired by {paired_by} needs the same {paired_by} "
                f"in both levels; leave out --paired-by to compare them unpaired")
        keep = np.asarray([k in both for k in keys]) & known
        dropped = int((known & ~keep).sum())
        if dropped:
            notes.append(f"{dropped} utterance(s) in {paired_by} blocks holding only one level left out")
        sel, group, spk, keys = sel[keep], group[keep], spk[keep], keys[keep]
        names = sorted(set(keys))
        stratum = np.asarray([names.index(k) for k in keys], dtype=np.int64)
        kind, unit, unit_group, unit_stratum = "within blocks", np.arange(len(sel)), group.astype(np.int64), stratum
        stratum_names = tuple(k.replace("\x1f", " / ") for k in names)
        boot = "blocks"
        paired = paired_by + (" and speaker" if combine else "")
    elif is_speaker_field or n_spk < 2:
        kind, unit, unit_group = "between utterances", np.arange(len(sel)), group.astype(np.int64)
        unit_stratum, stratum_names, boot, paired = np.zeros(len(sel), np.int64), ("all",), "cells", ""
    elif not varies_within:
        names = sorted(by_speaker)
        unit = np.asarray([names.index(s) for s in spk], dtype=np.int64)
        unit_group = np.asarray([next(iter(by_speaker[s])) for s in names], dtype=np.int64)
        a_spk = [s for s in names if by_speaker[s] == {0}]
        b_spk = [s for s in names if by_speaker[s] == {1}]
        notes.append(f"every speaker has one level of {by!r} ({level_a}: {', '.join(a_spk)}; {level_b}: "
                     f"{', '.join(b_spk)}): whole speakers are the unit, and the result is about "
                     f"{by!r} only as far as these speakers stand for their level")
        if len(a_spk) == 1 and len(b_spk) == 1:
            notes.append(f"each level of {by!r} is one speaker: a difference between the levels cannot be told from "
                         f"a difference between {a_spk[0]} and {b_spk[0]} (compare them with --by speaker)")
        kind, unit_stratum, stratum_names, boot, paired = ("between speakers", np.zeros(len(names), np.int64),
                                                           ("all",), "cells", "")
    else:
        mixed = sorted(s for s, v in by_speaker.items() if len(v) == 2)
        keep = np.asarray([s in mixed for s in spk])
        if (~keep).any():
            notes.append(f"{int((~keep).sum())} utterance(s) of speakers holding only one level left out")
        sel, group, spk = sel[keep], group[keep], spk[keep]
        stratum = np.asarray([mixed.index(s) for s in spk], dtype=np.int64)
        kind, unit, unit_group, unit_stratum = "within speaker", np.arange(len(sel)), group.astype(np.int64), stratum
        stratum_names, boot, paired = tuple(mixed), "cells", ""

    n_arr = _arrangements(unit_group, unit_stratum, len(stratum_names))
    testable = n_arr >= math.ceil(1.0 / alpha - 1e-9)
    if boot == "blocks":
        can_boot = len(stratum_names) >= 2
    else:
        cells = [int(((unit_stratum == s) & (unit_group == g)).sum())
                 for s in range(len(stratum_names)) for g in (0, 1)]
        can_boot = min(cells) >= 2
    reason = ""
    na, nb = int((unit_group == 0).sum()), int((unit_group == 1).sum())
    word = "speaker" if kind == "between speakers" else "utterance"
    if not testable:
        if na == 1 and nb == 1:
            start = f"one {word} per level ({level_a}: 1, {level_b}: 1)"
        else:
            start = f"{level_a} has {na} and {level_b} has {nb} {word}s"
            if kind in ("within blocks", "within speaker"):
                start += f" in {len(stratum_names)} {'blocks' if kind == 'within blocks' else 'speakers'}"
        reason = (f"{start}: whole {word}s are what is resampled, and their labels can be arranged in only {n_arr} "
                  f"way{'s' if n_arr != 1 else ''}, so no p-value can fall below {1.0 / n_arr:.2g} (a test at "
                  f"{alpha:g} needs at least {math.ceil(1.0 / alpha - 1e-9)} arrangements, e.g. "
                  f"{_needed(alpha)} {word}s per level). The estimates describe these {word}s only")
    elif not can_boot:
        notes.append("no intervals: some resampled cell holds a single unit, which a bootstrap cannot vary")
    return Design(by=by, level_a=level_a, level_b=level_b, paired_by=paired if paired_by else "", kind=kind,
                  utterances=sel.astype(np.int64), group=group.astype(np.int8),
                  speakers=np.asarray(spk, dtype=str) if len(spk) else np.zeros(0, str),
                  unit=np.asarray(unit, np.int64), unit_group=np.asarray(unit_group, np.int64),
                  unit_stratum=np.asarray(unit_stratum, np.int64), stratum_names=tuple(stratum_names),
                  bootstrap=boot, n_arrangements=n_arr, testable=bool(testable),
                  can_bootstrap=bool(can_boot and testable), reason=reason, notes=tuple(notes), alpha=float(alpha))


def _needed(alpha) -> int:
    """Units per level (equal) whose arrangements first reach 1 / alpha."""
    k = 1
    while math.comb(2 * k, k) < math.ceil(1.0 / alpha - 1e-9):
        k += 1
    return k
