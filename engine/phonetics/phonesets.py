"""Phone sets: one table relating ARPAbet, the paper's British set, SAMPA, IPA and MRPA.

A corpus keeps its own phone labels; this module says what they *are*. The table
``assets/phonesets.csv`` has one row per **canonical** phone — the lower-case,
ARPAbet-like British set of the paper's Table 1 (``p b m ch jh s z sh zh f v th dh k g
t d r w n ng hh l y aa ae ah ao aw ay ax ea eh ey ia ih iy oh ow oy ua uh``) plus ``uw``,
``er`` and the pause ``sil`` (the inventory of :mod:`engine.phonetics.phones`) — with its
place, manner, broad class, rounding, diphthong flag, the second paper's lip-reading
class, and the symbols of each phone set that denote it.

Matching a label (:func:`normalize`):

* **ARPAbet** (CMU, TIMIT, MFA's ``english_us_arpa``) matches case-insensitively. A
  trailing stress digit is tried first, then dropped: ``AH0`` -> ``ax`` and ``ER0`` ->
  ``ax`` (unstressed schwa; the British set is non-rhotic, as the paper uses ``ax``),
  ``AH1``/``AH`` -> ``ah``, ``ER1``/``ER`` -> ``er``. ``AA`` stays ``aa``: without the
  spelling the American *lot* vowel cannot be told from *palm* (see
  :func:`engine.phonetics.phones.cmu_to_paper` for the spelling-aware mapping).
* **SAMPA / X-SAMPA** (MAUS) and **IPA** (MFA's ``english_mfa``/``english_uk``) match
  case-sensitively. IPA labels lose tie bars, stress marks, the modifiers ``ʰ ʲ ʷ ˠ ˤ ˞``
  and syllabic / non-syllabic / dental / voiceless / nasal diacritics; a length mark
  ``ː`` is dropped when the long symbol itself is not in the table.
* **MRPA** (the CSTR machine-readable set of MOCHA-TIMIT ``.lab`` files: ``i`` kit,
  ``ii`` fleece, ``uh`` strut, ``u`` foot, ``@@`` nurse, ``o`` lot, ``oo`` thought)
  matches case-insensitively.
* **Pauses** — ``sil sp pau # h# epi silence <sil> <p:> <p> _ breath`` and the blank
  label — normalise to ``sil`` in every set (MOCHA's ``breath`` is not speech).

With no ``phoneset`` given, sets are tried in the order ARPAbet, IPA, SAMPA, MRPA.
Some symbols mean different phones in different sets — upper-case ``S T D N Z V`` in
ARPAbet and SAMPA, ``uh`` in ARPAbet (foot) and MRPA (strut), ``i`` in IPA (fleece)
and MRPA (kit) — and the earlier set wins. Pass ``phoneset=`` for labels of a known
set, or let :func:`detect_phoneset` choose from a whole corpus's labels.

Lip-reading classes (second paper, section 3): **protected** /f v m p/ (its list
repeats /v/; the four are kept), **invisible** /t d g k l/, **pause** for pauses, and
**normal** for all others (including /b/).
"""
from __future__ import annotations

import csv
import difflib
import functools
import re
import unicodedata
from dataclasses import dataclass
from typing import Any

from engine.files.assets import asset_path

__all__ = [
    "PhoneSetError", "PhoneInfo", "PHONESETS", "PAUSE", "UNKNOWN", "BROAD_CLASSES", "LIPREADING_CLASSES",
    "normalize", "phone_info", "broad_class", "lipreading_class", "place", "manner", "is_pause",
    "is_vowel", "is_rounded", "canonical_phones", "symbols", "to_phoneset", "detect_phoneset",
]

#: phone sets named in the table, in the order they are tried when none is given
PHONESETS = ("arpabet", "ipa", "sampa", "mrpa")
#: canonical pause label
PAUSE = "sil"
#: what the lenient (``strict=False``) functions return for a label no set knows
UNKNOWN = "unknown"
BROAD_CLASSES = ("bilabial", "labiodental", "dental", "alveolar", "postalveolar", "palatal", "velar", "glottal",
                 "approximant", "front vowel", "central vowel", "back vowel", "diphthong", "pause")
LIPREADING_CLASSES = ("protected", "invisible", "normal", "pause")
_COLUMNS = ("canonical", "place", "manner", "broad_class", "rounded", "diphthong", "lipreading",
            "arpabet", "sampa", "ipa", "mrpa", "note")
_FILE = "phonesets.csv"
#: sets matched case-insensitively
_CASELESS = ("arpabet", "mrpa")

_STRESS = re.compile(r"^(.*?[a-z])([0-2])$")
#: IPA marks that never change which English phone is meant
_IPA_DROP = dict.fromkeys(map(ord, "\u0361\u035c\u02c8\u02cc\u02b0\u02b2\u02b7\u02e0\u02e4\u02de"
                                   "\u0329\u030d\u032f\u032a\u031a\u0325\u0303"), None)
_IPA_LENGTH = dict.fromkeys(map(ord, "\u02d0\u02d1"), None)
_SAMPA_STRESS = dict.fromkeys(map(ord, "\"%'"), None)


class PhoneSetError(ValueError):
    """A phone label no phone set in the table knows, or a broken table file."""


@dataclass(frozen=True)
class PhoneInfo:
    """Everything the table says about one canonical phone."""

    canonical: str
    place: str
    manner: str
    broad_class: str
    rounded: bool
    diphthong: bool
    lipreading: str
    symbols: dict  # phone set -> tuple of symbols, primary first
    note: str = ""

    @property
    def is_vowel(self) -> bool:
        return self.place == "vowel"

    @property
    def is_pause(self) -> bool:
        return self.lipreading == "pause"


@dataclass(frozen=True)
class _Table:
    info: dict  # canonical -> PhoneInfo
    lookup: dict  # phone set -> {symbol (ARPAbet lower-cased) -> canonical}
    pauses: frozenset  # every pause symbol, ARPAbet ones lower-cased


@functools.lru_cache(maxsize=1)
def _table() -> _Table:
    return _load_table(asset_path(_FILE))


def _load_table(path) -> _Table:
    """Parse and check the table at ``path`` (errors name the file and line)."""
    with open(path, encoding="utf-8", newline="") as fh:
        lines = [(no, line) for no, line in enumerate(fh, 1) if line.strip() and not line.startswith("#")]
    if not lines:
        raise PhoneSetError(f"{path}: no rows; expected a header {','.join(_COLUMNS)} and one row per phone")
    rows = list(csv.reader([line for _, line in lines]))
    header = [c.strip() for c in rows[0]]
    missing = [c for c in _COLUMNS if c not in header]
    if missing:
        raise PhoneSetError(f"{path}:{lines[0][0]}: header lacks column(s) {', '.join(missing)}; "
                            f"expected {','.join(_COLUMNS)}")
    col = {c: header.index(c) for c in _COLUMNS}
    info: dict[str, Any]
    lookup: dict[str, dict[str, str]]
    info, lookup = {}, {s: {} for s in PHONESETS}
    pauses = set()
    for (no, _), row in zip(lines[1:], rows[1:]):
        where = f"{path}:{no}"
        if len(row) != len(header):
            raise PhoneSetError(f"{where}: {len(row)} cells, expected {len(header)} ({','.join(header)})")
        cell = {c: row[i].strip() for c, i in col.items()}
        canon = cell["canonical"]
        if not canon or canon in info:
            raise PhoneSetError(f"{where}: canonical phone {canon!r} is empty or repeated; each phone gets one row")
        if cell["broad_class"] not in BROAD_CLASSES:
            raise PhoneSetError(f"{where}: broad_class {cell['broad_class']!r} is not one of "
                                f"{', '.join(BROAD_CLASSES)}")
        if cell["lipreading"] not in LIPREADING_CLASSES:
            raise PhoneSetError(f"{where}: lipreading {cell['lipreading']!r} is not one of "
                                f"{', '.join(LIPREADING_CLASSES)}")
        for flag in ("rounded", "diphthong"):
            if cell[flag] not in ("0", "1"):
                raise PhoneSetError(f"{where}: {flag} must be 0 or 1, got {cell[flag]!r}")
        syms = {}
        for s in PHONESETS:
            syms[s] = tuple(cell[s].split())
            for sym in syms[s]:
                key = sym.lower() if s in _CASELESS else sym
                if lookup[s].get(key, canon) != canon:
                    raise PhoneSetError(f"{where}: {s} symbol {sym!r} already maps to {lookup[s][key]!r}; "
                                        "a symbol may denote one phone only")
                lookup[s][key] = canon
                if cell["lipreading"] == "pause":
                    pauses.add(key)
        info[canon] = PhoneInfo(canon, cell["place"], cell["manner"], cell["broad_class"], cell["rounded"] == "1",
                                cell["diphthong"] == "1", cell["lipreading"], syms, cell["note"])
    for canon in info:  # every canonical phone is also its own ARPAbet-like symbol
        lookup["arpabet"].setdefault(canon, canon)
    return _Table(info, lookup, frozenset(pauses))


# ----------------------------------------------------------------------- matching
def _check_set(phoneset):
    if phoneset is None:
        return PHONESETS
    if phoneset not in PHONESETS:
        raise ValueError(f"unknown phone set {phoneset!r}; use one of {', '.join(PHONESETS)} or None (try all)")
    return (phoneset,)


def _match(label: str, phoneset: str, table: _Table):
    m = table.lookup[phoneset]
    if phoneset == "arpabet":
        key = label.lower()
        if key in m:
            return m[key]
        st = _STRESS.match(key)
        return m.get(st.group(1)) if st else None
    if phoneset == "mrpa":
        return m.get(label.lower())
    if phoneset == "sampa":
        return m.get(label) or m.get(label.translate(_SAMPA_STRESS))
    key = unicodedata.normalize("NFC", label).translate(_IPA_DROP)
    return m.get(key) or m.get(key.translate(_IPA_LENGTH))


def _unknown(label, phoneset, table):
    sets = _check_set(phoneset)
    pool = sorted({sym for s in sets for sym in table.lookup[s]} | set(table.info))
    close = difflib.get_close_matches(str(label).lower() if phoneset in (None, *_CASELESS) else str(label), pool, n=4)
    near = f" Close symbols: {', '.join(close)}." if close else ""
    which = "any phone set (ARPAbet, IPA, SAMPA, MRPA)" if phoneset is None else f"the {phoneset} set"
    return PhoneSetError(
        f"unknown phone label {label!r}: not in {which} of {asset_path(_FILE)}.{near} Expected ARPAbet "
        "(AH0, SH, with or without stress digits), the paper's set (ax, ea, oh, sil), SAMPA (@, S, {) or IPA "
        "(ə, ʃ, æ) or MOCHA's MRPA (ii, @@); pass phoneset= to pick one set, strict=False to get 'unknown', "
        "or add the symbol to the table.")


def normalize(label, *, strict: bool = True, phoneset: str | None = None) -> str:
    """Canonical lower-case symbol of ``label`` (the paper's British set, plus uw, er, sil).

    Parameters
    ----------
    label : str
        A phone label of any set in the table; stress digits, IPA diacritics and case
        (ARPAbet) are handled as the module docstring says. Blank labels are pauses.
    strict : bool, default=True
        Raise :class:`PhoneSetError` for a label no set knows; with ``False`` return
        ``"unknown"``.
    phoneset : {"arpabet", "ipa", "sampa", "mrpa"} or None
        Only this set (pauses are accepted in every set); None tries all, in
        :data:`PHONESETS` order.

    Returns
    -------
    str
    """
    table = _table()
    if not isinstance(label, str):
        raise TypeError(f"phone label must be a str, got {type(label).__name__} {label!r}")
    lab = label.strip()
    if not lab or lab.lower() in table.pauses or lab in table.pauses:
        return PAUSE
    for s in _check_set(phoneset):
        canon = _match(lab, s, table)
        if canon is not None:
            return canon
    if strict:
        raise _unknown(label, phoneset, table)
    return UNKNOWN


def phone_info(label, *, strict: bool = True, phoneset: str | None = None) -> PhoneInfo | None:
    """The table row of ``label`` (None for an unknown label when ``strict=False``)."""
    canon = normalize(label, strict=strict, phoneset=phoneset)
    return _table().info.get(canon)


def _field(label, name, strict, phoneset):
    info = phone_info(label, strict=strict, phoneset=phoneset)
    return UNKNOWN if info is None else getattr(info, name)


def broad_class(label, *, strict: bool = True, phoneset: str | None = None) -> str:
    """One of :data:`BROAD_CLASSES` (place for consonants, vowel position, diphthong, pause)."""
    return _field(label, "broad_class", strict, phoneset)


def lipreading_class(label, *, strict: bool = True, phoneset: str | None = None) -> str:
    """``"protected"`` (/f v m p/), ``"invisible"`` (/t d g k l/), ``"pause"`` or ``"normal"``."""
    return _field(label, "lipreading", strict, phoneset)


def place(label, *, strict: bool = True, phoneset: str | None = None) -> str:
    """Place of articulation (``labial-velar`` for w, ``vowel``, ``pause``), as
    :data:`engine.phonetics.phones.PLACE`."""
    return _field(label, "place", strict, phoneset)


def manner(label, *, strict: bool = True, phoneset: str | None = None) -> str:
    """Manner (plosive, nasal, fricative, affricate, approximant; vowels reduced/short/long/diphthong; pause)."""
    return _field(label, "manner", strict, phoneset)


def is_pause(label, *, phoneset: str | None = None) -> bool:
    """Whether ``label`` is a pause (never raises: an unknown label is not a pause)."""
    return normalize(label, strict=False, phoneset=phoneset) == PAUSE


def is_vowel(label, *, strict: bool = True, phoneset: str | None = None) -> bool:
    info = phone_info(label, strict=strict, phoneset=phoneset)
    return bool(info is not None and info.is_vowel)


def is_rounded(label, *, strict: bool = True, phoneset: str | None = None) -> bool:
    """Lips rounded or protruded (rounded vowels, w, and the labialised r sh zh ch jh)."""
    info = phone_info(label, strict=strict, phoneset=phoneset)
    return bool(info is not None and info.rounded)


def canonical_phones() -> tuple[str, ...]:
    """Every canonical phone, in table order."""
    return tuple(_table().info)


def symbols(phone, phoneset: str) -> tuple[str, ...]:
    """Symbols of ``phoneset`` that denote ``phone`` (any label of it), primary first."""
    _check_set(phoneset)
    return _table().info[normalize(phone)].symbols[phoneset]


def to_phoneset(label, phoneset: str, *, strict: bool = True) -> str:
    """The primary ``phoneset`` symbol of ``label`` (ARPAbet in upper case, e.g. ``ax`` -> ``AX``).

    Raises :class:`PhoneSetError` when the set has no symbol for the phone (IPA has none
    for the pause); with ``strict=False`` the canonical symbol is returned instead.
    """
    canon = normalize(label, strict=strict)
    if canon == UNKNOWN:
        return canon
    syms = symbols(canon, phoneset)
    if not syms:
        if strict:
            raise PhoneSetError(f"the {phoneset} set has no symbol for {canon!r} ({label!r}); "
                                "use strict=False to keep the canonical symbol")
        return canon
    return syms[0].upper() if phoneset == "arpabet" else syms[0]


def detect_phoneset(labels) -> str:
    """The set that recognises most distinct ``labels`` (ties in :data:`PHONESETS` order).

    Useful for a whole corpus: SAMPA corpora give themselves away by ``@``, ``{``, ``I``
    or ``tS``, which ARPAbet lacks, so their ``S``/``T``/``D``/``N``/``Z`` are read as
    SAMPA; MOCHA's MRPA by ``ii``, ``@@`` or ``i@``, so its ``uh`` is read as strut.
    Pauses do not count. Returns ``"arpabet"`` when nothing is recognised.
    """
    table = _table()
    distinct = {str(x).strip() for x in set(labels.tolist() if hasattr(labels, "tolist") else labels)}
    distinct = {x for x in distinct if x and x.lower() not in table.pauses and x not in table.pauses}
    score = {s: sum(_match(x, s, table) is not None for x in distinct) for s in PHONESETS}
    return max(PHONESETS, key=lambda s: (score[s], -PHONESETS.index(s)))
