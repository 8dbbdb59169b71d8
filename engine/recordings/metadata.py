"""Per-utterance metadata: named fields such as speaker, sex, emotion, text, session or group.

A lab's corpus says who spoke each recording and under which condition, in the file
names (``XYZFIA01.mat``: speaker ``XYZ``, sex ``F``, emotion ``IA``, text ``01``) or in a
table kept beside the recordings. Each utterance carries its fields as
``Utterance.fields``, a tuple of ``(name, value)`` pairs; ``speaker`` is one such field,
kept in ``Utterance.speaker`` (the build normalises per speaker). A value of ``""`` is
missing (R's ``NA`` in the tables).

This module is the one place that reads them:

* :func:`utterance_fields` / :func:`with_fields`: one utterance's fields, and a copy with
  fields set;
* :func:`field_names`, :func:`field_values`, :func:`field_levels`, :func:`frame_levels`,
  :func:`utterances_by_level`, :func:`require_field`: the fields of a corpus, for ``info``,
  the tables, ``evaluate`` and comparisons between levels;
* how they are stored in a corpus file is :mod:`engine.recordings.field_arrays`.

Where fields come from (a file-name pattern, a metadata table) is
:mod:`engine.recordings.metadata_sources`.
"""
from __future__ import annotations

import re
from dataclasses import replace

import numpy as np

from engine.recordings.corpus import CorpusError, CorpusWarning

__all__ = ["MetadataError", "MetadataWarning", "FIELD_NAME", "RESERVED_NAMES", "check_field_name",
           "utterance_fields", "with_fields", "field_names", "field_values", "field_levels", "frame_levels",
           "utterances_by_level", "require_field", "describe_fields"]

#: what a field name looks like (it becomes a column of the tidy tables)
FIELD_NAME = re.compile(r"[a-z][a-z0-9_]*")
#: names the tables use for their own columns: a field may not take them
RESERVED_NAMES = frozenset({
    "utterance", "time_s", "frame", "phone", "landmark", "lip_aperture", "opening_fx1", "class", "state", "s", "v",
    "track", "gesture", "kind", "unit", "id", "start", "stop",
})


class MetadataError(CorpusError):
    """Metadata that cannot be used; the message names the file, line or field and the fix."""


class MetadataWarning(CorpusWarning):
    """Metadata that is usable but incomplete (files without a row, rows without a file)."""


def check_field_name(name: str, *, where: str = "") -> str:
    """``name`` if it can be a field (lower-case snake_case, not a table column), else MetadataError."""
    prefix = f"{where}: " if where else ""
    if not FIELD_NAME.fullmatch(name):
        raise MetadataError(f"{prefix}field name {name!r}: expected lower-case letters, digits and '_', starting "
                            "with a letter (it becomes a column of the tables), e.g. 'speaker' or 'emotion'")
    if name in RESERVED_NAMES or re.fullmatch(r"f[xy]_[0-9]+", name):
        raise MetadataError(f"{prefix}field name {name!r} is a column the tables already have; rename it "
                            "(e.g. 'condition', 'speaker_group')")
    return name


# ---------------------------------------------------------------- one utterance
def utterance_fields(u) -> dict[str, str]:
    """``{name: value}`` of utterance ``u``: ``speaker`` first (when named), then ``u.fields`` in order."""
    out = {"speaker": u.speaker} if u.speaker else {}
    out.update((k, v) for k, v in u.fields if v != "")
    return out


def with_fields(u, fields) -> object:
    """A copy of utterance ``u`` with ``fields`` (mapping or pairs) set; ``speaker`` goes to ``u.speaker``.

    Fields ``u`` already has keep their place; new ones are appended in the order given.
    An empty value removes the field.
    """
    items = list(fields.items()) if hasattr(fields, "items") else list(fields)
    own = dict(u.fields)
    speaker = u.speaker
    for k, v in items:
        k, v = str(k), "" if v is None else str(v).strip()
        if k == "speaker":
            speaker = v
        else:
            own[k] = v
    pairs = tuple((k, v) for k, v in own.items() if v != "")
    return replace(u, speaker=speaker, fields=pairs)


# ---------------------------------------------------------------- a corpus
def field_names(corpus) -> list[str]:
    """Names of the fields any utterance of ``corpus`` has: ``speaker`` first, then in first-seen order."""
    names = {"speaker": None} if any(u.speaker for u in corpus.utterances) else {}
    for u in corpus.utterances:
        for k, v in u.fields:
            if v != "":
                names.setdefault(k, None)
    return list(names)


def require_field(corpus, name: str) -> str:
    """``name`` if some utterance of ``corpus`` has that field, else MetadataError naming the fields it has."""
    known = field_names(corpus)
    if name not in known:
        have = ", ".join(known) if known else "none (import with --fields-from or --metadata)"
        raise MetadataError(f"{corpus.name}: no utterance has a field {name!r}; its fields: {have}")
    return name


def field_values(corpus, name: str) -> np.ndarray:
    """The value of field ``name`` for every utterance, ndarray of str (U,) ("" = missing)."""
    require_field(corpus, name)
    if name == "speaker":
        return np.array([u.speaker for u in corpus.utterances], dtype=str)
    return np.array([dict(u.fields).get(name, "") for u in corpus.utterances], dtype=str)


def field_levels(corpus, name: str) -> list[tuple[str, int, int]]:
    """``[(level, n utterances, n frames), ...]`` of field ``name``, most utterances first ("" = missing, last)."""
    vals = field_values(corpus, name)
    lengths = np.diff(corpus.bounds, axis=1)[:, 0]
    out: dict[str, tuple[int, int]] = {}
    for v, n in zip(vals.tolist(), lengths.tolist()):
        a, b = out.get(v, (0, 0))
        out[v] = (a + 1, b + int(n))
    order = sorted(out, key=lambda k: (k == "", -out[k][0], _natural(k)))
    return [(k, out[k][0], out[k][1]) for k in order]


def utterances_by_level(corpus, name: str) -> dict[str, list[str]]:
    """``{level: [utterance id, ...]}`` of field ``name`` in corpus order (utterances missing it under "")."""
    out: dict[str, list[str]] = {}
    for u, v in zip(corpus.utterances, field_values(corpus, name).tolist()):
        out.setdefault(v, []).append(u.id)
    return out


def frame_levels(corpus, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Field ``name`` per frame: ``(codes (N,) int64, levels (L,) str)``; ``levels[codes[i]]`` is frame i's
    level, code -1 where its utterance has none. Levels in :func:`field_levels` order."""
    levels = [lv for lv, _, _ in field_levels(corpus, name) if lv != ""]
    code = {lv: i for i, lv in enumerate(levels)}
    per_utt = np.array([code.get(v, -1) for v in field_values(corpus, name).tolist()], dtype=np.int64)
    lengths = np.diff(corpus.bounds, axis=1)[:, 0]
    return np.repeat(per_utt, lengths), np.array(levels, dtype=str)


def describe_fields(corpus, *, limit: int = 8) -> list[str]:
    """One line per field: its levels with utterance counts (``emotion 7 levels: AN 47, DI 46, ...``)."""
    n = len(corpus.utterances)
    lines = []
    for name in field_names(corpus):
        levels = field_levels(corpus, name)
        shown = [(lv, k) for lv, k, _ in levels if lv != ""]
        missing = next((k for lv, k, _ in levels if lv == ""), 0)
        text = ", ".join(f"{lv} {k}" for lv, k in shown[:limit]) + (" ..." if len(shown) > limit else "")
        tail = f"; missing in {missing} of {n} utterances" if missing else ""
        lines.append(f"{name} {len(shown)} level{'s' * (len(shown) != 1)}: {text}{tail}")
    return lines


def _natural(s: str):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]
