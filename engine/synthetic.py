"""The embedded default corpus: a deterministic synthetic talker.

Sentences are random word sequences from ``assets/wordlist.txt`` pronounced with the
CMU dictionary (:mod:`engine.phonetics`), with a pause ``sil`` at the start and end
and durations from :class:`~engine.phonetics.DurationModel`. Each phone sets targets
for six articulatory controls (:data:`engine.lipmodel.CONTROL_NAMES`); the targets of
neighbouring phones are blended by Cohen & Massaro (1993) dominance functions
(bilabials and labiodentals are protected: their closure / lip-to-teeth dominance is
twenty times that of other phones), then passed through second-order, critically
damped articulator dynamics (one natural frequency per control) with anticipation
of the system's lag, plus small motor noise. The controls drive the parametric lip
surface of :mod:`engine.lipmodel`; measurement noise is added to the points.

Plosives and the nasal differ in timing as the paper's Fig. 4 finds in real lips:
the closure gesture of /p b/ peaks early in the phone and releases quickly (the
burst), so their mid-points lie in the opening phase; /m/'s closure peaks late in
the phone, so its mid-point lies in the closing phase.

``Corpus.latent`` holds the controls after dynamics (``jaw``, ``round``, ``spread``,
``raise``, ``closure``, ``labiodental``) and ``aperture``, the vertical distance (mm)
between the upper and lower inner-lip midline points of the noise-free surface.
"""
from __future__ import annotations

import functools
import hashlib
import json
import math
import numbers
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.signal import lfilter, lfilter_zi
from sklearn.base import BaseEstimator

from engine.assets import asset_path
from engine.corpus import Corpus, CorpusError, PhoneInterval, Utterance
from engine.lipmodel import CONTROL_NAMES, RESOLUTIONS, LipModel
from engine.phonetics import PAUSE, DurationModel, pronounce
from engine.progress import report

__all__ = ["GENERATOR_VERSION", "PRESETS", "HELD_OUT_TALKER", "SyntheticTalker", "load_synthetic", "cache_folder",
           "phone_gestures"]

#: Bumped whenever the generated corpus changes for the same parameters (cache key).
GENERATOR_VERSION = 3

#: Preset: seconds of speech (frames = seconds * rate) and lip-surface resolution.
PRESETS = {
    "small": {"duration": 75.0, "resolution": "small"},
    "default": {"duration": 480.0, "resolution": "default"},
    "paper": {"duration": 28833 / 60.0, "resolution": "paper"},
}

# ---------------------------------------------------------------- phone targets
# control order: jaw, round, spread, raise, closure, labiodental
_J, _R, _S, _U, _C, _L = range(6)
#: Time to reach 63 % of a step (s) per control; natural frequency w = 2.146 / T63.
T63 = np.array([0.060, 0.080, 0.070, 0.065, 0.060, 0.045])
_WINDOW = 8  # gestures either side of a sample that contribute to its blend
_TIMING_SD = 0.08  # s.d. of a gesture's timing, as a fraction of its phone's duration
_SHAPE = np.array([1.5, 1.5, 1.5, 1.5, 2.0, 2.0])  # dominance exponent c per control

#: A second, independently parameterised talker (``SyntheticTalker(**HELD_OUT_TALKER)``):
#: another seed, faster speech, sloppier gesture timing, slower articulators, narrower
#: coarticulation, more target jitter and noise. The method's defaults were never tuned
#: on it; tests and docs/RESULTS.md use it as held-out data.
HELD_OUT_TALKER = {"seed": 7, "tempo": 1.15, "timing_sd": 0.12, "dynamics_scale": 1.3, "coarticulation": 0.8,
                   "jitter": 0.06, "noise": 0.05}
#: defaults of the keyword-only generator-variant parameters (left out of the cache key at
#: these values, so the default talker's cache files keep their names)
_VARIANT_DEFAULTS = {"timing_sd": _TIMING_SD, "dynamics_scale": 1.0, "coarticulation": 1.0}


@dataclass(frozen=True)
class Gesture:
    """One articulatory target of a phone, reached at ``frac`` of its duration
    (a number, or one per control)."""

    frac: float | tuple
    target: tuple  # (6,)
    alpha: tuple   # (6,) dominance magnitudes
    before: tuple  # (6,) (a, b): dominance width = a * duration + b before the centre
    after: tuple   # (6,) same after the centre


def _vowel(*subs):
    """Vowel gestures from (jaw, round, spread, raise) targets, one or two (diphthong)."""
    fracs = (0.5,) if len(subs) == 1 else (0.3, 0.8)
    out = []
    for f, (j, r, s, u) in zip(fracs, subs):
        tgt = (j, r, s, u, 0.0, 0.0)
        alpha = (1.0, 1.0, 1.0, 0.8, 1.0, 1.0)
        w = ((0.5, 0.03),) * 6
        out.append(Gesture(f, tgt, alpha, w, w))
    return tuple(out)


def _cons(jaw=(0.2, 0.4), rnd=(0.1, 0.15), spr=(0.1, 0.15), rai=(0.1, 0.3), clo=(0.0, 0.6),
          lab=(0.0, 0.6), frac=0.5, before=None, after=None, jaw_frac=None):
    tgt = tuple(v[0] for v in (jaw, rnd, spr, rai, clo, lab))
    alpha = tuple(v[1] for v in (jaw, rnd, spr, rai, clo, lab))
    w = [(0.5, 0.03)] * 6
    if rnd[0] > 0.4:
        wb = list(w)
        wb[_R] = (1.0, 0.08)  # anticipatory rounding reaches further back
    else:
        wb = list(w)
    b = tuple(before) if before else tuple(wb)
    a = tuple(after) if after else tuple(w)
    if jaw_frac is not None:
        frac = (jaw_frac,) + (frac,) * 5
    return (Gesture(frac, tgt, alpha, b, a),)


def _with(widths, k, val):
    widths = list(widths)
    widths[k] = val
    return tuple(widths)


_W0 = ((0.5, 0.03),) * 6
_PROTECT = 20.0

#: Gestures of every phone (targets 0..1 in the order of CONTROL_NAMES).
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
    **dict.fromkeys(("p", "b"), _cons(jaw=(0.02, 2.5), rnd=(0.1, 0.1), spr=(0.1, 0.1), rai=(0.0, 0.3),
                                      clo=(1.0, _PROTECT), frac=0.3,
                                      before=_with(_W0, _C, (0.45, 0.01)), after=_with(_W0, _C, (0.2, 0.004)))),
    # bilabial nasal: closure approached through the phone and reached late; the jaw
    # keeps rising past the phone's end, so the whole lip-jaw complex is still closing
    "m": _cons(jaw=(0.02, 2.5), rnd=(0.1, 0.1), spr=(0.1, 0.1), rai=(0.0, 0.3), clo=(1.0, _PROTECT),
               frac=0.75, jaw_frac=1.3, before=_with(_W0, _C, (0.5, 0.01)), after=_with(_W0, _C, (0.45, 0.02))),
    **dict.fromkeys(("f", "v"), _cons(jaw=(0.12, 0.6), rai=(0.25, 0.5), lab=(1.0, _PROTECT), frac=0.45,
                                      before=_with(_W0, _L, (0.4, 0.01)), after=_with(_W0, _L, (0.35, 0.01)))),
    **dict.fromkeys(("th", "dh"), _cons(jaw=(0.22, 0.5), spr=(0.2, 0.2), rai=(0.25, 0.3))),
    **dict.fromkeys(("s", "z"), _cons(jaw=(0.08, 1.2), spr=(0.35, 0.4), rai=(0.2, 0.3))),
    **dict.fromkeys(("t", "d"), _cons(jaw=(0.15, 0.7))),
    **dict.fromkeys(("n", "l"), _cons(jaw=(0.2, 0.5))),
    **dict.fromkeys(("sh", "zh", "ch", "jh"), _cons(jaw=(0.12, 0.8), rnd=(0.65, 1.2), rai=(0.35, 0.6))),
    "r": _cons(jaw=(0.2, 0.4), rnd=(0.55, 1.0)),
    "w": _cons(jaw=(0.12, 0.8), rnd=(1.0, 3.0)),
    "y": _cons(jaw=(0.12, 0.6), spr=(0.55, 0.8)),
    **dict.fromkeys(("k", "g", "ng"), _cons(jaw=(0.25, 0.3))),
    "hh": _cons(jaw=(0.3, 0.1), rnd=(0.1, 0.05), spr=(0.1, 0.05), rai=(0.1, 0.05), clo=(0.0, 0.3), lab=(0.0, 0.3)),
    # pause: lips lightly together, jaw almost closed
    PAUSE: _cons(jaw=(0.02, 1.5), rnd=(0.05, 0.6), spr=(0.1, 0.6), rai=(0.05, 0.6), clo=(0.7, 1.5), lab=(0.0, 1.0)),
}


def phone_gestures(phone: str) -> tuple:
    """Articulatory gestures of ``phone`` (tuple of :class:`Gesture`)."""
    try:
        return PHONE_GESTURES[phone]
    except KeyError:
        raise ValueError(f"no articulatory targets for phone {phone!r}; known: {' '.join(sorted(PHONE_GESTURES))}") from None


# ------------------------------------------------------------------ word list
@functools.lru_cache(maxsize=1)
def _lexicon() -> tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]:
    path = asset_path("wordlist.txt")
    words = [w.strip() for w in path.read_text(encoding="utf-8").splitlines()]
    words = [w for w in words if w and not w.startswith("#")]
    prons = tuple(tuple(pronounce(w)) for w in words)
    keep = [i for i, p in enumerate(prons) if p]
    return tuple(words[i] for i in keep), tuple(prons[i] for i in keep)


# ---------------------------------------------------------------- the talker
class SyntheticTalker(BaseEstimator):
    """Deterministic synthetic talker producing a phone-aligned 3D lip corpus.

    Parameters
    ----------
    preset : {"small", "default", "paper"}
        ``"small"``: 75 s, 156 points (tests); ``"default"``: 8 minutes (28,800
        frames at 60 Hz), 600 points; ``"paper"``: 28,833 frames, 4,260 points.
    n_sentences : int or None
        Generate exactly this many sentences instead of the preset's duration.
    duration : float or None
        Seconds of speech (overrides the preset); the frame count is exactly
        ``round(duration * rate)``.
    resolution : str or (int, int) or None
        Lip-surface resolution (overrides the preset), see :class:`LipModel`.
    rate : float
        Frame rate (Hz).
    seed : int
        Seed of the random generator; same parameters give identical corpora.
    noise : float
        Standard deviation (mm) of measurement noise added to each coordinate
        (independent, uniformly distributed).
    jitter : float
        Standard deviation of per-phone random variation of the control targets.
    tempo : float
        Speaking-rate factor of the duration model.
    timing_sd : float, default=0.08
        Standard deviation of a gesture's timing, as a fraction of its phone's duration.
    dynamics_scale : float, default=1.0
        Factor on every articulator's time constant (> 1: slower, smoother lips).
    coarticulation : float, default=1.0
        Factor on every dominance width (< 1: less overlap between neighbouring phones).
    """

    def __init__(self, *, preset="default", n_sentences=None, duration=None, resolution=None, rate=60.0,
                 seed=0, noise=0.03, jitter=0.04, tempo=1.0, timing_sd=_TIMING_SD, dynamics_scale=1.0,
                 coarticulation=1.0):
        self.preset = preset
        self.n_sentences = n_sentences
        self.duration = duration
        self.resolution = resolution
        self.rate = rate
        self.seed = seed
        self.noise = noise
        self.jitter = jitter
        self.tempo = tempo
        self.timing_sd = timing_sd
        self.dynamics_scale = dynamics_scale
        self.coarticulation = coarticulation

    # -------------------------------------------------------------- validation
    def _validate(self):
        if self.preset not in PRESETS:
            raise ValueError(f"unknown preset {self.preset!r}; use one of {sorted(PRESETS)}")
        if not (isinstance(self.rate, numbers.Real) and 10 <= self.rate <= 1000):
            raise ValueError(f"rate must be a frame rate in Hz between 10 and 1000, got {self.rate!r}")
        if self.n_sentences is not None and (int(self.n_sentences) != self.n_sentences or self.n_sentences < 1):
            raise ValueError(f"n_sentences must be a positive integer or None, got {self.n_sentences!r}")
        dur = PRESETS[self.preset]["duration"] if self.duration is None else float(self.duration)
        if not (np.isfinite(dur) and dur >= 3.0):
            raise ValueError(f"duration must be at least 3 s of speech, got {dur!r}")
        if not (np.isfinite(self.noise) and self.noise >= 0):
            raise ValueError(f"noise must be >= 0 mm, got {self.noise!r}")
        if not (np.isfinite(self.jitter) and 0 <= self.jitter <= 0.5):
            raise ValueError(f"jitter must be in [0, 0.5], got {self.jitter!r}")
        if not (np.isfinite(self.timing_sd) and 0 <= self.timing_sd <= 0.5):
            raise ValueError(f"timing_sd must be in [0, 0.5] (fraction of a phone), got {self.timing_sd!r}")
        for name in ("dynamics_scale", "coarticulation"):
            v = getattr(self, name)
            if not (np.isfinite(v) and 0.25 <= v <= 4.0):
                raise ValueError(f"{name} must be a factor in [0.25, 4], got {v!r}")
        res = PRESETS[self.preset]["resolution"] if self.resolution is None else self.resolution
        return dur, res

    # -------------------------------------------------------------- sentences
    def _sentence(self, rng, dm, words, prons, n_words):
        idx = rng.integers(0, len(words), size=n_words)
        phones, text = [PAUSE], []
        for k, i in enumerate(idx):
            if k and rng.random() < 0.08:
                phones.append(PAUSE)
            phones.extend(prons[i])
            text.append(words[i])
        phones.append(PAUSE)
        d = dm.durations(phones, rng)
        d[0] = rng.uniform(0.2, 0.4)
        d[-1] = rng.uniform(0.25, 0.45)
        inner = [k for k in range(1, len(phones) - 1) if phones[k] == PAUSE]
        if inner:
            d[inner] = rng.uniform(0.12, 0.25, size=len(inner))
        # phrase-final lengthening of the two phones before a pause
        for k in range(1, len(phones)):
            if phones[k] == PAUSE and phones[k - 1] != PAUSE:
                d[k - 1] *= 1.3
                if k >= 2 and phones[k - 2] != PAUSE:
                    d[k - 2] *= 1.1
        sentence = " ".join(text)
        return phones, d, sentence[:1].upper() + sentence[1:] + "."

    def _sentences(self, rng, total_frames):
        words, prons = _lexicon()
        dm = DurationModel(tempo=self.tempo)
        rate = float(self.rate)
        out = []
        if self.n_sentences is not None:
            for _ in range(int(self.n_sentences)):
                ph, d, txt = self._sentence(rng, dm, words, prons, int(rng.integers(4, 11)))
                out.append((ph, d, txt, max(2, int(round(d.sum() * rate)))))
            return out
        remaining = total_frames
        while True:
            ph, d, txt = self._sentence(rng, dm, words, prons, int(rng.integers(4, 11)))
            nf = max(2, int(round(d.sum() * rate)))
            if nf <= remaining - 1.5 * rate:
                out.append((ph, d, txt, nf))
                remaining -= nf
                continue
            # last sentence: fill the remaining frames exactly
            phones, durs, text = [PAUSE], [rng.uniform(0.2, 0.3)], []
            tail_min = 0.15
            while True:
                i = int(rng.integers(0, len(words)))
                dw = dm.durations(prons[i], rng)
                if text and sum(durs) + dw.sum() + tail_min > remaining / rate:
                    break
                phones.extend(prons[i])
                durs.extend(dw)
                text.append(words[i])
                if sum(durs) + tail_min > remaining / rate:
                    break
            budget = remaining / rate - tail_min
            if sum(durs) > budget:  # one long word in a short remainder: speak it faster
                durs = [x * budget / sum(durs) for x in durs]
            phones.append(PAUSE)
            durs.append(remaining / rate - sum(durs))
            sentence = " ".join(text)
            out.append((phones, np.array(durs), sentence[:1].upper() + sentence[1:] + ".", remaining))
            return out

    # -------------------------------------------------------------- articulation
    def _controls(self, rng, phones, durs, n_frames):
        """Controls after dynamics for one utterance, ndarray (n_frames, 6)."""
        rate = float(self.rate)
        sub = max(1, math.ceil(240.0 / rate))
        fs = rate * sub
        starts = np.concatenate([[0.0], np.cumsum(durs)[:-1]])
        cen, tgt, alp, wb, wa = [], [], [], [], []
        for p, s, d in zip(phones, starts, durs):
            for g in phone_gestures(p):
                frac = np.broadcast_to(np.asarray(g.frac, dtype=float), (6,))
                jit = frac + float(self.timing_sd) * rng.standard_normal()
                cen.append(s + np.clip(jit, np.minimum(frac, 0.0), np.maximum(frac, 1.0)) * d)
                tgt.append(g.target)
                alp.append(g.alpha)
                wb.append([(a * d + b) * self.coarticulation for a, b in g.before])
                wa.append([(a * d + b) * self.coarticulation for a, b in g.after])
        cen = np.array(cen)                                                      # (E, 6)
        tgt = np.clip(np.array(tgt) + self.jitter * rng.standard_normal((len(cen), 6)), 0.0, 1.0)
        alp, wb, wa = np.array(alp), np.array(wb), np.array(wa)
        omega = 2.146 / (T63 * float(self.dynamics_scale))
        lead = 2.0 / omega                                   # group delay of the dynamics
        n_sub = n_frames * sub
        t = np.arange(n_sub) / fs
        # each sample sees the _WINDOW gestures either side of it (sorted by centre)
        order = np.argsort(cen.mean(1), kind="stable")
        cen, tgt, alp, wb, wa = cen[order], tgt[order], alp[order], wb[order], wa[order]
        near = np.searchsorted(cen.mean(1), t)[:, None] + np.arange(-_WINDOW, _WINDOW)[None, :]   # (n, 2W)
        valid = (near >= 0) & (near < len(cen))
        near = np.clip(near, 0, len(cen) - 1)
        tau = t[:, None, None] + lead[None, None, :] - cen[near]                 # (n, 2W, 6)
        w = np.where(tau < 0, wb[near], wa[near])
        dom = alp[near] * np.exp(-(np.abs(tau) / w) ** _SHAPE) * valid[:, :, None]
        u = (dom * tgt[near]).sum(1) / (dom.sum(1) + 1e-12)                    # (n, 6)
        u += 0.02 * rng.standard_normal(u.shape)                               # motor noise
        p = np.exp(-omega / fs)
        out = np.empty_like(u)
        for k in range(6):
            b, a = [1 - p[k]], [1.0, -p[k]]
            zi = lfilter_zi(b, a)
            y, _ = lfilter(b, a, u[:, k], zi=zi * u[0, k])
            y, _ = lfilter(b, a, y, zi=zi * u[0, k])
            out[:, k] = y
        return np.clip(out[::sub], 0.0, 1.0)

    # -------------------------------------------------------------- generate
    def generate(self, progress=None) -> Corpus:
        """Generate the corpus.

        Parameters
        ----------
        progress : callable(stage, done, total) or None

        Returns
        -------
        Corpus
            ``frames`` (n_frames, 3 * n_points) float32 in mm, ``faces``,
            ``point_names``, phone-aligned utterances ``s0001``..., and ``latent``.
        """
        dur, res = self._validate()
        rng = np.random.default_rng(self.seed)
        rate = float(self.rate)
        lip = LipModel(res)
        total = int(round(dur * rate))
        report(progress, "sentences", 0, 1)
        sents = self._sentences(rng, total)
        report(progress, "sentences", 1, 1)
        ctrls, utts, pos = [], [], 0
        for k, (ph, d, txt, nf) in enumerate(sents):
            report(progress, "articulation", k, len(sents))
            ctrls.append(self._controls(rng, ph, d, nf))
            ends = np.cumsum(d)
            ends[-1] = nf / rate
            st = np.concatenate([[0.0], ends[:-1]])
            phones = tuple(PhoneInterval(float(a), float(b), p) for a, b, p in zip(st, ends, ph))
            utts.append(Utterance(f"s{k + 1:04d}", pos, pos + nf, phones, None, txt))
            pos += nf
        report(progress, "articulation", len(sents), len(sents))
        C = np.concatenate(ctrls)
        n = C.shape[0]
        frames = np.empty((n, 3 * lip.n_points), dtype=np.float32)
        chunk = max(1, 4_000_000 // (3 * lip.n_points))
        for s in range(0, n, chunk):
            report(progress, "geometry", s, n)
            blk = frames[s:s + chunk]
            lip.deform(C[s:s + chunk], out=blk)
            if self.noise > 0:  # uniform measurement noise of s.d. `noise` (7x cheaper than normal)
                buf = rng.random(blk.shape, dtype=np.float32)
                buf -= np.float32(0.5)
                buf *= np.float32(self.noise * math.sqrt(12.0))
                blk += buf
        report(progress, "geometry", n, n)
        latent = {name: C[:, k].astype(np.float64) for k, name in enumerate(CONTROL_NAMES)}
        latent["aperture"] = lip.aperture(C)
        self.n_frames_ = int(n)
        self.n_points_ = int(lip.n_points)
        self.n_utterances_ = len(utts)
        return Corpus(frames=frames, rate=rate, utterances=utts, dims=3, faces=lip.faces,
                      point_names=lip.point_names, latent=latent, name=f"synthetic-{self.preset}")


# ------------------------------------------------------------------ caching
def cache_folder(override=None) -> Path:
    """Folder of cached corpora: ``override``, else ``$LIPSPACE_CACHE_DIR``, else the
    platform's user cache folder for ``lipspace``."""
    if override is not None:
        return Path(override)
    env = os.environ.get("LIPSPACE_CACHE_DIR")
    if env:
        return Path(env)
    import platformdirs

    return Path(platformdirs.user_cache_dir("lipspace"))


def generator_fingerprint() -> str:
    """A hash of the synthetic talker's code (this module, the lip model, the phonetics)."""
    from engine._persist import source_fingerprint

    return source_fingerprint(("engine.synthetic", "engine.lipmodel", "engine.phonetics", "engine.corpus"))


def _cache_key(params: dict) -> str:
    # the generator's code is part of the key: an edit without a GENERATOR_VERSION bump still regenerates
    blob = json.dumps({"version": GENERATOR_VERSION, "code": generator_fingerprint(), **params}, sort_keys=True,
                      default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


def load_synthetic(*, preset="default", progress=None, cache_dir=None, **params) -> Corpus:
    """The synthetic corpus for ``preset``, generated once and cached.

    Parameters
    ----------
    preset : {"small", "default", "paper"}
    progress : callable(stage, done, total) or None
    cache_dir : path or None
        Overrides ``$LIPSPACE_CACHE_DIR`` and the user cache folder.
    **params
        Further :class:`SyntheticTalker` parameters (``seed``, ``n_sentences``, ...).

    Returns
    -------
    Corpus
    """
    talker = SyntheticTalker(preset=preset, **params)
    talker._validate()
    folder = cache_folder(cache_dir)
    key = {k: v for k, v in talker.get_params().items() if not (k in _VARIANT_DEFAULTS and v == _VARIANT_DEFAULTS[k])}
    path = folder / f"synthetic-{preset}-{_cache_key(key)}.npz"
    if path.is_file():
        report(progress, "loading cache", 0, 1)
        try:
            corpus = Corpus.load(path)
            report(progress, "loading cache", 1, 1)
            return corpus
        except (CorpusError, OSError, ValueError):
            pass  # damaged cache file: regenerate it
    corpus = talker.generate(progress=progress)
    try:
        report(progress, "saving cache", 0, 1)
        corpus.save(path)
        report(progress, "saving cache", 1, 1)
    except OSError:
        pass  # a read-only cache folder only costs regeneration next time
    return corpus
