"""Haskins / MVIEW EMA structs (``.mat``), e.g. the Haskins IEEE rate corpus.

A MATLAB v5 file holds one struct array (named after the file) with fields ``NAME``,
``SRATE``, ``SIGNAL`` (and ``SOURCE``, ``SENTENCE``, ``WORDS``, ``PHONES``, ``LABELS``).
Entry ``AUDIO`` is the sound (44.1 kHz); each sensor entry (``TR TB TT UL LL ML JAW
JAWL``) has ``SIGNAL`` of shape (n, 6) at 100 Hz whose first three columns are x
(anterior +), y (lateral), z (vertical) in mm. The first entry also holds ``SENTENCE``
and ``PHONES`` (``LABEL``, ``OFFS`` = [start, end] in seconds; ARPAbet with stress digits,
``sp`` = pause), kept as given, and ``WORDS`` (the same form), the utterance's word tier.

The file is parsed by :mod:`engine.io.readers.matfile` (bounds-checked), not ``scipy.io.loadmat``,
which can crash the interpreter on a damaged file.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from engine._deprecated import deprecated_names
from engine.io._util import check_rate, one_utterance_corpus, plausible_rate, sidecar_audio
from engine.io._util import fill_gaps as _fill_gaps
from engine.io.errors import ImportFormatError
from engine.io.readers.alignment import resolve_alignment
from engine.io.readers.matfile import MatStruct, read_mat
from engine.io.repairs import reports_repairs
from engine.recordings.corpus import PhoneInterval

__all__ = ["read_mview", "read_mview_audio", "MVIEW_LIP_SENSORS"]

# the writer moved to engine.io.writers.audio; this old home still gives it, with a warning
__getattr__ = deprecated_names(__name__, {"write_audio": ("engine.io.writers.audio", "write_audio")})

#: default selection: upper lip, lower lip, left mouth corner, jaw (central incisor), jaw left
MVIEW_LIP_SENSORS = ("UL", "LL", "ML", "JAW", "JAWL")


def _is_mview(v) -> bool:
    return isinstance(v, MatStruct) and {"NAME", "SRATE", "SIGNAL"} <= set(v.fields)


def _load_struct(path, notes=None) -> MatStruct:
    m = read_mat(path, notes=notes)
    names = [k for k in m if not k.startswith("__")]
    want = Path(path).stem
    structs = [k for k in names if _is_mview(m[k])]
    if len(structs) > 1:  # which recording the file holds cannot be told: never one picked without a word
        raise ImportFormatError(path, f"holds {len(structs)} MVIEW struct arrays ({', '.join(map(repr, structs[:8]))}"
                                f"); expected one, named after the file ({want!r}): save each recording in its own "
                                "file")
    key = want if want in names else (names[0] if len(names) == 1 else structs[0] if structs else None)
    if key is None:
        raise ImportFormatError(path, f"holds variables {names[:8]}; expected one MVIEW struct array named {want!r}")
    s = m[key]
    if isinstance(s, np.ndarray) and s.ndim == 2 and np.issubdtype(s.dtype, np.number):
        raise ImportFormatError(path, f"variable {key!r} is a plain {s.shape[0]} x {s.shape[1]} numeric matrix, "
                                "not an MVIEW struct array; read it with a sensor layout: layout= "
                                "(lipspace import --layout ema7x6 | ema7x7 | LAYOUT_FILE --rate HZ)")
    fields = s.fields if isinstance(s, MatStruct) else []
    for f in ("NAME", "SRATE", "SIGNAL"):
        if f not in fields:
            raise ImportFormatError(path, f"variable {key!r} has fields {list(fields)[:10]}; expected an MVIEW "
                                    "struct array with NAME, SRATE and SIGNAL")
    if not len(s):
        raise ImportFormatError(path, f"variable {key!r} is an empty struct array; expected sensor entries")
    return s


def _text(v) -> str:
    if isinstance(v, str):
        return v
    if isinstance(v, list) and v and all(isinstance(x, str) for x in v):
        return v[0]
    return ""


def _number(v) -> float | None:
    """The one real number ``v`` holds; None for anything else (several values, a complex or empty one)."""
    if not isinstance(v, np.ndarray) or v.size != 1 or not np.issubdtype(v.dtype, np.number):
        return None
    x = v.ravel()[0]
    if np.iscomplexobj(v) and np.imag(x) != 0:
        return None
    return float(np.real(x))


def _entries(path, notes=None):
    s = _load_struct(path, notes)
    out, twice = {}, {}
    for i, e in enumerate(s):
        name = _text(e["NAME"]).strip()
        if name:
            if name.upper() in out:
                twice[name.upper()] = (out[name.upper()][0], i)
            out.setdefault(name.upper(), (i, e))
    return s, _Entries(path, out, twice)


class _Entries(dict):
    """Sensor entries by NAME; using a NAME that two entries carry is refused."""

    def __init__(self, path, entries, twice):
        super().__init__(entries)
        self.path, self.twice = path, twice

    def __getitem__(self, name):
        if name in self.twice:
            a, b = self.twice[name]
            raise ImportFormatError(self.path, f"entries {a + 1} and {b + 1} are both named {name!r}; expected one "
                                    "entry per sensor")
        return super().__getitem__(name)


def _phones(entry0, path, field: str = "PHONES") -> tuple[list[PhoneInterval], str]:
    """The intervals of ``field`` (``PHONES`` or ``WORDS``: ``LABEL`` and ``OFFS`` = [start end] s) and the sentence."""
    text = _text(entry0.get("SENTENCE", "")).strip()
    ph = entry0.get(field)
    what = "phone" if field == "PHONES" else "word"
    if not isinstance(ph, MatStruct) or not len(ph):
        return [], text
    if not {"LABEL", "OFFS"} <= set(ph.fields):
        raise ImportFormatError(path, f"{field} has no LABEL / OFFS fields; expected MVIEW {what} labels")
    out: list[PhoneInterval] = []
    p: Any
    for k, p in enumerate(ph):  # type: ignore[arg-type]  # a MatStruct iterates over its entries
        offs = p["OFFS"]
        lab = _text(p["LABEL"]).strip()
        if not isinstance(offs, np.ndarray) or offs.size != 2 or not np.issubdtype(offs.dtype, np.number):
            raise ImportFormatError(path, f"{field}({k + 1}) {lab!r}: OFFS is {offs!r}; expected [start end] in "
                                    "seconds")
        s, e = (float(np.real(x)) for x in offs.ravel())
        if not (np.isfinite(s) and np.isfinite(e)) or e < s:
            raise ImportFormatError(path, f"{field}({k + 1}) {lab!r} has times {s!r}-{e!r}; expected finite "
                                    "start <= end in seconds")
        if out and s < out[-1].end - 1e-6:
            raise ImportFormatError(path, f"{field}({k + 1}) {lab!r} starts at {s:g} s before the previous {what} "
                                    f"ends at {out[-1].end:g} s; expected {what}s in time order")
        out.append(PhoneInterval(s, e, lab))
    return out, text


@reports_repairs
def read_mview(path, *, sensors=MVIEW_LIP_SENSORS, rate: float | None = None, alignment=None,
               tier: str | None = None, fill_gaps: bool = True):
    """A Haskins / MVIEW ``.mat`` file as a 3-D corpus of lip and jaw sensors.

    Parameters
    ----------
    path : str or Path
    sensors : sequence of str or "all"
        Sensor entries to keep, in order (default :data:`MVIEW_LIP_SENSORS`); ``"all"``
        keeps every non-audio entry with an (n, >=3) signal.
    rate : float, optional
        Only checked against the file's ``SRATE``.
    alignment : None, False, path or sequence of PhoneInterval
        None: the file's own ``PHONES`` (or ``<stem>.TextGrid``/``.lab`` beside it when the
        file has none); a path: that alignment instead.
    tier : str, optional
    fill_gaps : bool
        Interpolate NaN dropouts; else raise naming the frame.

    Returns
    -------
    Corpus
        One utterance named after the file (text = ``SENTENCE``), frames (n, 3 * n_sensors)
        in mm, x anterior, y lateral, z vertical; audio ``<stem>.wav`` when present
        (see :func:`engine.io.writers.audio.write_audio`).
    """
    path = Path(path)
    damage: list[str] = []
    s, ent = _entries(path, damage)
    if isinstance(sensors, str) and sensors == "all":
        want = [n for n, (i, e) in ent.items()
                if n != "AUDIO" and isinstance(e["SIGNAL"], np.ndarray) and e["SIGNAL"].ndim == 2
                and e["SIGNAL"].shape[1] >= 3]
    else:
        want = [str(x).upper() for x in sensors]
    missing = [n for n in want if n not in ent]
    if missing or not want:
        raise ImportFormatError(path, f"has no sensor entries {missing}; it has {sorted(ent)}")
    sigs, rates = [], []
    for n in want:
        i, e = ent[n]
        sig = e["SIGNAL"]
        r = _number(e["SRATE"])
        if not isinstance(sig, np.ndarray) or sig.ndim != 2 or sig.shape[1] < 3 or \
                not np.issubdtype(sig.dtype, np.number) or np.iscomplexobj(sig):
            raise ImportFormatError(path, f"entry {i + 1} ({n}) SIGNAL is {getattr(sig, 'shape', type(sig))} "
                                    f"{getattr(sig, 'dtype', '')}; "
                                    "expected numbers of shape (n_frames, >=3) holding x, y, z")
        if r is None:
            got = e["SRATE"]
            shown = np.array2string(got, threshold=6) if isinstance(got, np.ndarray) else repr(got)
            raise ImportFormatError(path, f"entry {i + 1} ({n}) SRATE is {shown[:120]}; expected one rate in Hz "
                                    "(a single real number)")
        r = plausible_rate(path, r, f"entry {i + 1} ({n}) SRATE")
        sigs.append(sig[:, :3].astype(np.float64))
        rates.append(r)
    if len(set(rates)) > 1 or len({g.shape[0] for g in sigs}) > 1:
        desc = ", ".join(f"{n} {g.shape[0]} @ {r:g} Hz" for n, g, r in zip(want, sigs, rates))
        raise ImportFormatError(path, f"sensors differ in rate or length ({desc}); expected one rate and length")
    native = check_rate(path, rates[0], rate)
    X = np.concatenate(sigs, axis=1)
    cols = [f"{n}_{a}" for n in want for a in "xyz"]
    frames = _fill_gaps(X, np.zeros(len(X), bool), path=path, names=cols, fill=fill_gaps)
    own, text = _phones(s[0], path)
    if alignment is None and own:
        phones = own
    else:
        phones, _ = resolve_alignment(path, alignment, tier=tier)
    c = one_utterance_corpus(path, frames, native, dims=3, phones=phones, point_names=want,
                             audio=sidecar_audio(path), text=text)
    words, _ = _phones(s[0], path, "WORDS")
    if words:  # the word tier, inside the recording
        end = c.n_frames / native
        kept = tuple(PhoneInterval(w.start, min(w.end, end), w.label) for w in words if w.start < end)
        c = replace(c, utterances=[replace(u, words=kept) for u in c.utterances])
    c.history.extend(f"{path.name}: {d}" for d in damage)  # what a damaged file still gave
    return c


def read_mview_audio(path) -> tuple[np.ndarray, float]:
    """The ``AUDIO`` entry of an MVIEW file: samples (n,) float32 and rate (Hz)."""
    _, ent = _entries(Path(path))
    if "AUDIO" not in ent:
        raise ImportFormatError(path, f"has no AUDIO entry; it has {sorted(ent)}")
    i, e = ent["AUDIO"]
    x = e["SIGNAL"]
    r = _number(e["SRATE"])
    if not isinstance(x, np.ndarray) or x.ndim not in (1, 2) or x.size == 0 or np.iscomplexobj(x) or \
            not np.issubdtype(x.dtype, np.number) or r is None:
        raise ImportFormatError(path, f"entry {i + 1} (AUDIO) holds {getattr(x, 'shape', 'no array')} at {r!r} Hz; "
                                "expected a mono signal and a positive SRATE")
    r = plausible_rate(path, r, f"entry {i + 1} (AUDIO) SRATE", audio=True)
    with np.errstate(over="ignore", invalid="ignore"):
        return x.reshape(x.shape[0], -1)[:, 0].astype(np.float32), float(r)
