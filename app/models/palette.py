"""One categorical palette per session: the colour of every level of every kind of category.

A *kind* is what the levels name: ``"phone"``, ``"landmark"``, ``"speaker"``, ``"class"``
(the four tangent classes), ``"utterance"``, or ``"field:NAME"`` for a per-utterance metadata
field. Each level of a kind gets one colour for the whole session, the same in the
manifold view, its legend, the clusters table's swatches, the timeline and every figure,
because all of them ask one :class:`SessionPalette`.

How colours are given, so that the same corpus gives the same colours in the window and
from ``lipspace figures``:

* the levels of a kind are ranked once, most frequent first (ties by name), by
  :meth:`SessionPalette.for_corpus`; level ``k`` of that ranking takes colour ``k`` of
  :func:`qualitative_colours`. A level never seen in the corpus (a phone typed by hand)
  takes the next free colour the first time it is asked for, and keeps it;
* the sequence starts with the seven chromatic colours of Okabe & Ito's colour-blind-safe
  set (black is left out: black draws the original trajectory); each later colour is the
  sRGB colour farthest, in CIELAB, from every colour before it as seen with normal vision
  and under simulated deuteranopia and protanopia (Machado et al. 2009, severity 1), with
  greys and near-white left out (grey means "no value" and "dimmed" in the explorer). Past
  about a dozen levels no palette keeps every colour apart for every reader: the legend,
  the filter and the tooltips name them;
* the tangent classes keep fixed colours that carry their 2 x 2 design: opening warm,
  closing cool, accelerating dark, decelerating light (legible in greyscale by lightness).

Free of Qt, VTK and matplotlib.
"""
from __future__ import annotations

import functools
from collections.abc import Iterable, Mapping

import numpy as np

__all__ = ["OKABE_ITO", "CLASS_COLOURS", "CLASS_LABELS", "LANDMARK_ORDER", "SessionPalette", "qualitative_colours",
           "to_hex", "srgb_to_lab", "simulate_cvd"]

RGB = tuple[float, float, float]

#: Okabe & Ito's colour-blind-safe set without black: orange, sky blue, bluish green, yellow, blue,
#: vermillion, reddish purple
OKABE_ITO: tuple[str, ...] = ("#E69F00", "#56B4E9", "#009E73", "#F0E442", "#0072B2", "#D55E00", "#CC79A7")

#: the four tangent classes (``engine.manifold.tangent`` classes 0..3)
CLASS_LABELS = ("opening / accelerating", "opening / decelerating", "closing / accelerating",
                "closing / decelerating")
CLASS_COLOURS: tuple[str, ...] = ("#B2182B", "#F4A582", "#2166AC", "#92C5DE")

#: kinematic and gestural landmark labels in the order of a gesture: they take colours in this order
LANDMARK_ORDER = ("open", "opening", "closing", "closed", "gesture onset", "peak velocity (to target)",
                  "nucleus onset", "maximum constriction", "nucleus offset", "peak velocity (away)",
                  "gesture offset")

#: Machado, Oliveira & Fernandes (2009) simulation matrices at severity 1, in linear RGB
_CVD = {
    "deuteranopia": np.array([[0.367322, 0.860646, -0.227968], [0.280085, 0.672501, 0.047413],
                              [-0.011820, 0.042940, 0.968881]]),
    "protanopia": np.array([[0.152286, 1.052583, -0.204868], [0.114503, 0.786281, 0.099216],
                            [-0.003882, -0.048116, 1.051998]]),
    "tritanopia": np.array([[1.255528, -0.076749, -0.178779], [-0.078411, 0.930809, 0.147602],
                            [0.004733, 0.691367, 0.303900]]),
}
#: how many colours the sequence holds before it repeats
_LONGEST = 64


def to_hex(rgb) -> str:
    """``'#RRGGBB'`` of an sRGB colour with components in [0, 1]."""
    r, g, b = (int(round(float(np.clip(c, 0, 1)) * 255)) for c in rgb)
    return f"#{r:02X}{g:02X}{b:02X}"


def _rgb(colour) -> RGB:
    if isinstance(colour, str):
        s = colour.lstrip("#")
        if len(s) != 6:
            raise ValueError(f"colour {colour!r} is not #RRGGBB")
        return tuple(int(s[i:i + 2], 16) / 255.0 for i in (0, 2, 4))  # type: ignore[return-value]
    r, g, b = (float(c) for c in colour)
    return (r, g, b)


def _linear(rgb) -> np.ndarray:
    c = np.asarray(rgb, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _encode(lin) -> np.ndarray:
    lin = np.clip(lin, 0.0, 1.0)
    return np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)


def simulate_cvd(rgb, kind: str = "deuteranopia") -> np.ndarray:
    """sRGB colours (..., 3) as seen with colour-vision deficiency ``kind`` (Machado et al. 2009)."""
    if kind not in _CVD:
        raise ValueError(f"kind must be one of {sorted(_CVD)}, got {kind!r}")
    return _encode(_linear(rgb) @ _CVD[kind].T)


def srgb_to_lab(rgb) -> np.ndarray:
    """sRGB in [0, 1] (..., 3) -> CIELAB (D65)."""
    xyz = _linear(rgb) @ np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722],
                                   [0.0193, 0.1192, 0.9505]]).T / np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], -1)


def _views(rgb) -> np.ndarray:
    """CIELAB of ``rgb`` (n, 3) as seen normally, by a deuteranope and by a protanope: (3, n, 3)."""
    return np.stack([srgb_to_lab(rgb), srgb_to_lab(simulate_cvd(rgb, "deuteranopia")),
                     srgb_to_lab(simulate_cvd(rgb, "protanopia"))])


@functools.lru_cache(maxsize=1)
def _sequence() -> np.ndarray:
    """The palette's colours (_LONGEST, 3), float64, read-only (see the module docstring)."""
    g = np.linspace(0.0, 1.0, 18)
    cand = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    lab = srgb_to_lab(cand)
    chroma = np.hypot(lab[:, 1], lab[:, 2])
    # no greys (no value / dimmed), nothing near white (the background) or near black (the original trajectory)
    cand = cand[(chroma > 25) & (lab[:, 0] > 25) & (lab[:, 0] < 88)]
    views = _views(cand)
    chosen = [_rgb(c) for c in OKABE_ITO]
    nearest = np.full(len(cand), np.inf)
    for c in chosen:
        v = _views(np.asarray([c]))
        nearest = np.minimum(nearest, np.linalg.norm(views - v, axis=-1).min(axis=0))
    while len(chosen) < _LONGEST:
        k = int(np.argmax(nearest))
        chosen.append(tuple(float(x) for x in cand[k]))
        nearest = np.minimum(nearest, np.linalg.norm(views - views[:, k:k + 1], axis=-1).min(axis=0))
    out = np.asarray(chosen, dtype=np.float64)
    out.setflags(write=False)
    return out


def qualitative_colours(n: int) -> np.ndarray:
    """The first ``n`` colours of the palette's sequence, shape (n, 3), float32 in [0, 1].

    The first seven are Okabe & Ito's; the sequence repeats after 64 colours.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
        raise ValueError(f"n must be a non-negative integer, got {n!r}")
    seq = _sequence()
    return np.asarray(seq[np.arange(int(n)) % len(seq)], dtype=np.float32)


def _ranked_by(levels, weights) -> list[str]:
    """Distinct ``levels``, heaviest total weight first, ties by name (the empty level left out).

    Levels are coded by hashing (:func:`engine.recordings.corpus.label_codes`), not by sorting
    every string: a ten-million-frame corpus has 1.6 million phones."""
    from engine.recordings.corpus import label_codes

    if len(levels) == 0:
        return []
    names, inv = label_codes(levels)
    total = np.bincount(inv.ravel(), weights=np.asarray(weights, dtype=np.float64), minlength=len(names))
    order = sorted(range(len(names)), key=lambda i: (-float(total[i]), str(names[i])))
    return [str(names[i]) for i in order if str(names[i]) != ""]


class SessionPalette:
    """The colour of each level of each kind of category, given once and never changed.

    Parameters
    ----------
    ranking : mapping of str to sequence of str, optional
        For each kind, its levels in the order they take colours (most frequent first).
    fixed : mapping of str to mapping of str to colour, optional
        Colours that do not come from the sequence (the tangent classes'); a colour is a
        ``#RRGGBB`` string or three floats in [0, 1].

    Examples
    --------
    >>> p = SessionPalette(ranking={"phone": ["sil", "ax", "p"]})
    >>> p.hex("phone", "sil")
    '#E69F00'
    >>> p.hex("phone", "zz") == p.hex("phone", "zz") != p.hex("phone", "p")
    True
    """

    def __init__(self, *, ranking: Mapping[str, Iterable[str]] | None = None,
                 fixed: Mapping[str, Mapping[str, object]] | None = None):
        self._index: dict[str, dict[str, int]] = {}
        self._fixed: dict[str, dict[str, RGB]] = {"class": {n: _rgb(c) for n, c in zip(CLASS_LABELS, CLASS_COLOURS)}}
        for kind, levels in (fixed or {}).items():
            self._fixed[str(kind)] = {str(k): _rgb(v) for k, v in levels.items()}
        self.rank("landmark", LANDMARK_ORDER)
        for kind, levels in (ranking or {}).items():
            self.rank(kind, levels)

    # ---------------------------------------------------------------------------- building
    @classmethod
    def for_corpus(cls, corpus, *, fields: Mapping[str, Iterable[str]] | None = None) -> SessionPalette:
        """The palette of ``corpus``: phones ranked by the frames they span, speakers and utterances by
        their frame counts, each metadata field's levels by their utterance counts.

        Parameters
        ----------
        corpus : engine.recordings.corpus.Corpus
        fields : mapping of str to sequence of str, optional
            Per-utterance metadata: for each field name, one level per utterance.
        """
        _mid, labels, _utt, start, stop = corpus.phone_table()
        ranking = {"phone": _ranked_by(labels, np.maximum(np.asarray(stop) - np.asarray(start), 1))}
        lengths = np.asarray([u.stop - u.start for u in corpus.utterances])
        ranking["speaker"] = _ranked_by([str(getattr(u, "speaker", "") or "") for u in corpus.utterances], lengths)
        ranking["utterance"] = _ranked_by([str(u.id) for u in corpus.utterances], lengths)
        for name, values in (fields or {}).items():
            values = [str(v) for v in values]
            ranking[f"field:{name}"] = _ranked_by(values, np.ones(len(values)))
        return cls(ranking=ranking)

    def rank(self, kind: str, levels: Iterable[str]) -> None:
        """Give the levels of ``kind`` not yet coloured the next free colours, in the order given."""
        table = self._index.setdefault(str(kind), {})
        for level in levels:
            level = str(level)
            if level not in table and level not in self._fixed.get(str(kind), {}):
                table[level] = len(table)

    # ---------------------------------------------------------------------------- reading
    def colour(self, kind: str, level) -> RGB:
        """The colour (r, g, b) in [0, 1] of ``level`` of ``kind``; a level not seen before takes the
        next free colour now and keeps it."""
        kind, level = str(kind), str(level)
        fixed = self._fixed.get(kind)
        if fixed is not None and level in fixed:
            return fixed[level]
        table = self._index.setdefault(kind, {})
        if level not in table:
            table[level] = len(table)
        seq = _sequence()
        return tuple(float(c) for c in seq[table[level] % len(seq)])  # type: ignore[return-value]

    def hex(self, kind: str, level) -> str:
        """``'#RRGGBB'`` of :meth:`colour`."""
        return to_hex(self.colour(kind, level))

    def colours(self, kind: str, levels: Iterable[str]) -> dict[str, RGB]:
        """``{level: (r, g, b)}`` for ``levels``, in the order given."""
        return {str(lv): self.colour(kind, lv) for lv in levels}

    def array(self, kind: str, levels: Iterable[str]) -> np.ndarray:
        """Colours of ``levels`` as an array (n, 3) float32."""
        cols = [self.colour(kind, lv) for lv in levels]
        return np.asarray(cols, dtype=np.float32).reshape(-1, 3)

    def levels(self, kind: str) -> list[str]:
        """The levels of ``kind`` coloured so far, in colour order."""
        fixed = list(self._fixed.get(str(kind), {}))
        table = self._index.get(str(kind), {})
        return fixed + sorted(table, key=table.__getitem__)

    @property
    def kinds(self) -> list[str]:
        """Every kind the palette knows."""
        return sorted(set(self._index) | set(self._fixed))

    # ---------------------------------------------------------------------------- saving
    def to_dict(self) -> dict:
        """A JSON-able record (for session files): each kind's levels in colour order."""
        return {"ranking": {k: self.levels(k)[len(self._fixed.get(k, {})):] for k in sorted(self._index)}}

    @classmethod
    def from_dict(cls, d: Mapping) -> SessionPalette:
        """The palette :meth:`to_dict` recorded; raises ValueError naming what is wrong."""
        if not isinstance(d, Mapping) or not isinstance(d.get("ranking"), Mapping):
            raise ValueError(f"a palette record is {{'ranking': {{kind: [levels]}}}}, got {type(d).__name__}")
        ranking = {}
        for kind, levels in d["ranking"].items():
            if not isinstance(levels, list) or not all(isinstance(v, str) for v in levels):
                raise ValueError(f"palette kind {kind!r}: levels must be a list of strings")
            ranking[str(kind)] = levels
        return cls(ranking=ranking)
