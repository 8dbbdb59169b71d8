"""How per-utterance metadata fields are stored in a corpus file.

Two text arrays beside the corpus's own: ``corpus_field_names`` (F,) and
``corpus_field_values`` (U, F), ``""`` where an utterance lacks a field. ``speaker`` is
stored on its own (``corpus_utt_speaker``), as before fields existed. Files written
before fields existed have neither array and load with no fields. Kept apart from
:mod:`engine.recordings.metadata` so that the corpus can read and write them without
importing what reads fields from file names and tables.
"""
from __future__ import annotations

import numpy as np

__all__ = ["fields_to_arrays", "fields_from_arrays"]


def fields_to_arrays(utterances) -> dict[str, np.ndarray]:
    """The fields of ``utterances`` (other than speaker) as corpus-file arrays; {} when none has any."""
    names: dict[str, None] = {}
    for u in utterances:
        for k, _ in u.fields:
            names.setdefault(k, None)
    if not names:
        return {}
    cols = list(names)
    rows = [[dict(u.fields).get(k, "") for k in cols] for u in utterances]
    return {"corpus_field_names": np.array(cols, dtype=str),
            "corpus_field_values": np.array(rows, dtype=str).reshape(len(rows), len(cols))}


def fields_from_arrays(d, n_utterances: int, *, source: str = "<arrays>") -> list[tuple] | None:
    """Per-utterance ``((name, value), ...)`` from corpus-file arrays (:func:`fields_to_arrays`); None when the
    file has none. Raises :class:`engine.files.validate.FieldError` naming the file and array when they do
    not fit the utterances."""
    from engine.files.validate import FieldError, check_array

    keys = set(d.keys())
    if "corpus_field_names" not in keys and "corpus_field_values" not in keys:
        return None
    dims = {"U": int(n_utterances)}
    names = check_array(d, "corpus_field_names", source=source, kind="str", shape=("F",), dims=dims).tolist()
    values = check_array(d, "corpus_field_values", source=source, kind="str", shape=("U", "F"), dims=dims)
    if len(set(names)) != len(names):
        raise FieldError(source, "corpus_field_names", f"repeats a name ({names}); expected each field once")
    return [tuple((str(k), str(v)) for k, v in zip(names, row) if v != "") for row in values.tolist()]
