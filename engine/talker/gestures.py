"""The articulatory gestures of the synthetic talker's phones.

Each phone sets targets for the fourteen articulatory controls
(:data:`engine.talker.lipmodel.CONTROL_NAMES`), each with a dominance magnitude and the widths
of its Cohen & Massaro (1993) dominance function before and after its centre
(:data:`PHONE_GESTURES`); bilabials and labiodentals are protected (their closure / lip-to-teeth
dominance is twenty times that of other phones). :func:`gesture_phases` gives the ground truth
of the lip gesture's phase per frame (opening or closing, accelerating or decelerating) from the
exact aperture, which the tests of the manifold's tangent classes compare against.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from engine.phonetics.phones import EXTRA_VOWELS, PAUSE, VOWELS
from engine.talker.lipmodel import CONTROL_NAMES

__all__ = ["Gesture", "PHONE_GESTURES", "phone_gestures", "gesture_phases"]

# control order: jaw, round, spread, raise, closure, labiodental, protrude, depress, corner, asymmetry, jaw_lateral,
# jaw_forward, roll, mentalis
_J, _R, _S, _U, _C, _L, _P, _D, _K, _A, _X, _F, _O, _M = range(14)
_NC = len(CONTROL_NAMES)
_LOOKAHEAD = (1.0, 0.15)  # dominance width (a * duration + b s) before a rounded / protruded phone


@dataclass(frozen=True)
class Gesture:
    """One articulatory target of a phone, reached at ``frac`` of its duration
    (a number, or one per control)."""

    frac: float | tuple
    target: tuple  # (14,)
    alpha: tuple   # (14,) dominance magnitudes
    before: tuple  # (14,) (a, b): dominance width = a * duration + b before the centre
    after: tuple   # (14,) same after the centre


#: one control of a gesture: (target, dominance magnitude), or a dominance width (a, b)
_Span = tuple[float, float]


def _vowel(*subs: tuple[float, ...]) -> tuple[Any, ...]:
    """Vowel gestures from (jaw, round, spread, raise) targets, one or two (diphthong).

    Protrusion goes with rounding (0.85 of it), the corners rise with spreading and fall
    a little with rounding, open vowels depress the lower lip a little, rounded vowels
    evert the vermilion (0.3 of the rounding) and pout with the chin (mentalis, 0.2)."""
    fracs = (0.5,) if len(subs) == 1 else (0.3, 0.8)
    out = []
    for f, (j, r, s, u) in zip(fracs, subs):
        tgt = (j, r, s, u, 0.0, 0.0, 0.85 * r, 0.3 * max(j - 0.5, 0.0), 0.4 * s - 0.2 * r, 0.0, 0.0, 0.0, 0.3 * r,
               0.2 * r)
        alpha = (1.0, 1.0, 1.0, 0.8, 1.0, 1.0, 1.0, 0.8, 0.6, 0.05, 0.05, 0.3, 0.5, 0.5)
        w = ((0.5, 0.03),) * _NC
        wb = _with(_with(w, _R, _LOOKAHEAD), _P, _LOOKAHEAD) if r > 0.4 else w
        out.append(Gesture(f, tgt, alpha, wb, w))
    return tuple(out)


def _cons(jaw: _Span = (0.2, 0.4), rnd: _Span = (0.1, 0.15), spr: _Span = (0.1, 0.15), rai: _Span = (0.1, 0.3),
          clo: _Span = (0.0, 0.6), lab: _Span = (0.0, 0.6), pro: _Span | None = None, dep: _Span = (0.0, 0.2),
          cor: _Span = (0.0, 0.2), jfw: _Span = (0.0, 0.3), rol: _Span = (0.0, 0.2), mnt: _Span = (0.0, 0.2),
          frac: Any = 0.5, before: Iterable[_Span] | None = None, after: Iterable[_Span] | None = None,
          jaw_frac: float | None = None) -> tuple[Any, ...]:
    if pro is None:
        pro = (0.85 * rnd[0], rnd[1])
    drift = ((0.0, 0.05), (0.0, 0.05))
    tgt = tuple(v[0] for v in (jaw, rnd, spr, rai, clo, lab, pro, dep, cor) + drift + (jfw, rol, mnt))
    alpha = tuple(v[1] for v in (jaw, rnd, spr, rai, clo, lab, pro, dep, cor) + drift + (jfw, rol, mnt))
    w = ((0.5, 0.03),) * _NC
    wb = w
    if rnd[0] > 0.4 or pro[0] > 0.4:  # anticipatory (look-ahead) rounding and protrusion
        wb = _with(_with(w, _R, _LOOKAHEAD), _P, _LOOKAHEAD)
    b = tuple(before) if before else wb
    a = tuple(after) if after else w
    if jaw_frac is not None:
        frac = (jaw_frac,) + (frac,) * (_NC - 1)
    return (Gesture(frac, tgt, alpha, b, a),)


def _with(widths: Iterable[Any], k: int, val: Any) -> tuple[Any, ...]:
    widths = list(widths)
    widths[k] = val
    return tuple(widths)


_W0 = ((0.5, 0.03),) * _NC
_PROTECT = 20.0

#: Gestures of every phone (targets in the order of CONTROL_NAMES: 0..1, the signed ones -1..1).
PHONE_GESTURES = {
    # vowels: (jaw, round, spread, raise)
    "iy": _vowel((0.12, 0.0, 0.8, 0.25)), "ih": _vowel((0.25, 0.0, 0.5, 0.2)),
    "eh": _vowel((0.45, 0.0, 0.35, 0.2)), "ae": _vowel((0.72, 0.0, 0.4, 0.3)),
    "aa": _vowel((0.9, 0.05, 0.05, 0.15)), "ah": _vowel((0.6, 0.0, 0.1, 0.15)),
    "ax": _vowel((0.35, 0.05, 0.1, 0.1)), "ao": _vowel((0.6, 0.75, 0.0, 0.1)),
    "oh": _vowel((0.7, 0.5, 0.0, 0.1)), "uh": _vowel((0.3, 0.55, 0.0, 0.1)),
    "uw": _vowel((0.2, 1.0, 0.0, 0.05)), "er": _vowel((0.35, 0.15, 0.15, 0.1)),
    "ey": _vowel((0.4, 0.0, 0.45, 0.2), (0.22, 0.0, 0.55, 0.2)),
    "ay": _vowel((0.85, 0.0, 0.1, 0.15), (0.3, 0.0, 0.5, 0.2)),
    "aw": _vowel((0.85, 0.0, 0.1, 0.15), (0.3, 0.7, 0.0, 0.1)),
    "oy": _vowel((0.6, 0.7, 0.0, 0.1), (0.28, 0.0, 0.45, 0.2)),
    "ow": _vowel((0.45, 0.35, 0.0, 0.1), (0.3, 0.75, 0.0, 0.1)),
    "ia": _vowel((0.25, 0.0, 0.5, 0.2), (0.38, 0.05, 0.1, 0.1)),
    "ea": _vowel((0.5, 0.0, 0.3, 0.2), (0.38, 0.05, 0.1, 0.1)),
    "ua": _vowel((0.3, 0.55, 0.0, 0.1), (0.38, 0.05, 0.1, 0.1)),
    # bilabial plosives: closure peaks early and releases fast (the burst)
    # (all bilabials are made with the jaw raised, with a dominant jaw target, so the jaw
    # does much of the closing as in real speech instead of the lips alone)
    # (the pressed lips roll the vermilion in, and the chin's mentalis helps raise the lower lip)
    **dict.fromkeys(("p", "b"), _cons(jaw=(0.02, 2.5), rnd=(0.1, 0.1), spr=(0.1, 0.1), rai=(0.0, 0.3),
                                      clo=(1.0, _PROTECT), rol=(-0.5, 1.0), mnt=(0.35, 0.8), frac=0.3,
                                      before=_with(_W0, _C, (0.45, 0.01)), after=_with(_W0, _C, (0.2, 0.004)))),
    # bilabial nasal: closure approached through the phone and reached late; the jaw
    # keeps rising past the phone's end, so the whole lip-jaw complex is still closing
    "m": _cons(jaw=(0.02, 2.5), rnd=(0.1, 0.1), spr=(0.1, 0.1), rai=(0.0, 0.3), clo=(1.0, _PROTECT),
               rol=(-0.4, 1.0), mnt=(0.3, 0.8), frac=0.75, jaw_frac=1.3, before=_with(_W0, _C, (0.5, 0.01)),
               after=_with(_W0, _C, (0.45, 0.02))),
    **dict.fromkeys(("f", "v"), _cons(jaw=(0.12, 0.6), rai=(0.25, 0.5), lab=(1.0, _PROTECT), jfw=(0.3, 0.5),
                                      rol=(-0.3, 0.6), frac=0.45,
                                      before=_with(_W0, _L, (0.4, 0.01)), after=_with(_W0, _L, (0.35, 0.01)))),
    # dental fricatives: the lower lip drops to let the tongue tip show
    **dict.fromkeys(("th", "dh"), _cons(jaw=(0.22, 0.5), spr=(0.2, 0.2), rai=(0.25, 0.3), dep=(0.35, 0.5),
                                        jfw=(0.4, 0.5))),
    **dict.fromkeys(("s", "z"), _cons(jaw=(0.08, 1.2), spr=(0.35, 0.4), rai=(0.2, 0.3), cor=(0.15, 0.3),
                                      jfw=(0.6, 0.8))),
    **dict.fromkeys(("t", "d"), _cons(jaw=(0.15, 0.7), jfw=(0.2, 0.3))),
    **dict.fromkeys(("n", "l"), _cons(jaw=(0.2, 0.5), jfw=(0.2, 0.3))),
    # postalveolars: strong protrusion with moderate rounding, both lips everted (funnel)
    **dict.fromkeys(("sh", "zh", "ch", "jh"), _cons(jaw=(0.12, 0.8), rnd=(0.5, 1.2), rai=(0.35, 0.6),
                                                    pro=(0.9, 1.5), dep=(0.4, 0.8), jfw=(0.5, 0.8), rol=(0.5, 0.8),
                                                    mnt=(0.2, 0.5))),
    "r": _cons(jaw=(0.2, 0.4), rnd=(0.55, 1.0), pro=(0.45, 0.8)),
    "w": _cons(jaw=(0.12, 0.8), rnd=(1.0, 3.0), pro=(0.8, 2.0), rol=(0.3, 0.5), mnt=(0.2, 0.5)),
    "y": _cons(jaw=(0.12, 0.6), spr=(0.55, 0.8), cor=(0.2, 0.4)),
    **dict.fromkeys(("k", "g", "ng"), _cons(jaw=(0.25, 0.3), jfw=(-0.2, 0.3))),
    "hh": _cons(jaw=(0.3, 0.1), rnd=(0.1, 0.05), spr=(0.1, 0.05), rai=(0.1, 0.05), clo=(0.0, 0.3), lab=(0.0, 0.3),
                pro=(0.1, 0.05), dep=(0.0, 0.05), cor=(0.0, 0.05), jfw=(0.0, 0.05), rol=(0.0, 0.05), mnt=(0.0, 0.05)),
    # pause: lips lightly together, jaw almost closed
    PAUSE: _cons(jaw=(0.02, 1.5), rnd=(0.05, 0.6), spr=(0.1, 0.6), rai=(0.05, 0.6), clo=(0.7, 1.5), lab=(0.0, 1.0),
                 pro=(0.0, 0.6), dep=(0.0, 0.6), cor=(0.0, 0.3), jfw=(0.0, 0.5), rol=(0.0, 0.3), mnt=(0.1, 0.3)),
}


_VOWELS = frozenset(VOWELS + EXTRA_VOWELS)


def phone_gestures(phone: str) -> tuple:
    """Articulatory gestures of ``phone`` (tuple of :class:`Gesture`)."""
    try:
        return PHONE_GESTURES[phone]
    except KeyError:
        known = " ".join(sorted(PHONE_GESTURES))
        raise ValueError(f"no articulatory targets for phone {phone!r}; known: {known}") from None


def gesture_phases(aperture: ArrayLike, bounds: ArrayLike) -> np.ndarray:
    """The ground-truth phase of the lip gesture per frame, from the exact aperture.

    Forward steps inside each utterance: opening when the aperture grows to the next
    frame (step v), accelerating when the change of velocity has the sign of the velocity,
    ``sign(v - v_prev) == sign(v)`` with ``v_prev`` the step into the frame (the engine's
    convention for its four classes, ``engine.manifold.tangent.CLASS_NAMES``; the first frame of
    an utterance takes its own step as ``v_prev``, so it counts as decelerating).

    Returns
    -------
    int8 ndarray of shape (n,): 0 opening/accelerating, 1 opening/decelerating,
    2 closing/accelerating, 3 closing/decelerating, -1 at the last frame of each
    utterance (no forward step).
    """
    a = np.asarray(aperture, np.float64)
    out = np.full(len(a), -1, np.int8)
    for s, e in np.asarray(bounds):
        if e - s < 2:
            continue
        v = np.diff(a[s:e])                 # forward step of frames s..e-2
        prev = np.r_[v[0], v[:-1]]          # step into the frame (the first frame repeats its own)
        acc = np.sign(v - prev) == np.sign(v)
        out[s:e - 1] = np.where(v > 0, np.where(acc, 0, 1), np.where(acc, 2, 3))
    return out

