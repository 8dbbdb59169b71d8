"""The synthetic talker: a deterministic estimator generating a phone-aligned 3D lip corpus.

Sentences are random word sequences from ``assets/wordlist.txt`` pronounced with the
CMU dictionary (:mod:`engine.phonetics.phones`), with a pause ``sil`` at the start and end
and durations from :class:`~engine.phonetics.phones.DurationModel`. Each phone sets targets
for the fourteen articulatory controls (:mod:`engine.talker.gestures`); the targets of
neighbouring phones are blended by Cohen & Massaro (1993) dominance functions
(bilabials and labiodentals are protected: their closure / lip-to-teeth dominance is
twenty times that of other phones), then passed through second-order, critically
damped articulator dynamics (one natural frequency per control) with anticipation
of the system's lag, plus small motor noise, a vowel's emphasis on its jaw opening and a
slow postural drift of the corners, asymmetry and lateral jaw. With ``tissue=True``
(opt-in) the lip tissue varies on its own too: phones drive vermilion roll and the chin's
mentalis, each token's lip gestures vary in size independently of one another, a vowel's
emphasis scales its lip gestures with its jaw, and each sentence has its own tissue
posture. The controls drive the parametric lip surface of :mod:`engine.talker.lipmodel`; capture
noise and registration error are added to the points.

Plosives and the nasal differ in timing as the paper's Fig. 4 finds in real lips:
the closure gesture of /p b/ peaks early in the phone and releases quickly (the
burst), so their mid-points lie in the opening phase; /m/'s closure peaks late in
the phone, so its mid-point lies in the closing phase.

``Corpus.latent`` holds the controls after dynamics (one entry per name of
:data:`engine.talker.lipmodel.CONTROL_NAMES`) and ``aperture``, the vertical distance (mm)
between the upper and lower inner-lip midline points of the noise-free surface.
"""
from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from numbers import Integral, Real
from typing import Any

import numpy as np

from engine.constraints import Condition, Interval, StrOptions, validate_params
from engine.estimator import Estimator
from engine.files.assets import asset_path
from engine.phonetics.phones import PAUSE, DurationModel, pronounce
from engine.progress import ProgressFn, report
from engine.recordings.corpus import Corpus, PhoneInterval, Utterance
from engine.talker.gestures import (
    _D,
    _F,
    _J,
    _K,
    _M,
    _NC,
    _O,
    _P,
    _R,
    _S,
    _U,
    _VOWELS,
    _X,
    gesture_phases,
    phone_gestures,
)
from engine.talker.lipmodel import CONTROL_NAMES, KINEMATICS, RESOLUTIONS, SIGNED_CONTROLS, Anatomy, LipModel
from engine.threads import one_blas_thread

__all__ = ["GENERATOR_VERSION", "PRESETS", "HELD_OUT_TALKER", "SyntheticTalker", "lip_roles", "speaker_anatomy"]

#: the lip model's coordinates (engine.talker.lipmodel): x the talker's left, y up, z forward, in mm
LIP_MODEL_AXES = "x=left,y=up,z=forward"

#: Bumped whenever the generated corpus changes for the same parameters (cache key).
GENERATOR_VERSION = 6

#: Preset: seconds of speech (frames = seconds * rate) and lip-surface resolution.
PRESETS: dict[str, dict[str, Any]] = {
    "small": {"duration": 75.0, "resolution": "small", "speakers": 1},
    "default": {"duration": 480.0, "resolution": "default", "speakers": 1},
    "paper": {"duration": 28833 / 60.0, "resolution": "paper", "speakers": 1},
    "multi": {"duration": 480.0, "resolution": "default", "speakers": 4},
}

# ---------------------------------------------------------------- articulator dynamics
_BASE = tuple(range(11))  # the controls that move in the default talker (all but jaw_forward, roll, mentalis)
#: Time to reach 63 % of a step (s) per control; natural frequency w = 2.146 / T63.
#: Protrusion is slower than rounding (Perkell 1986); corners, asymmetry and the lateral
#: jaw follow slow postural changes, the jaw's protrusion as its lateral shift; vermilion roll is
#: as fast as rounding (the same muscle), the chin (mentalis) as slow as protrusion.
T63 = np.array([0.060, 0.080, 0.070, 0.065, 0.060, 0.045, 0.100, 0.060, 0.150, 0.300, 0.120, 0.120, 0.080, 0.100])
_WINDOW = 8  # gestures either side of a sample that contribute to its blend
_TIMING_SD = 0.08  # s.d. of a gesture's timing, as a fraction of its phone's duration
#: dominance exponent c per control
_SHAPE = np.array([1.5, 1.5, 1.5, 1.5, 2.0, 2.0, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5])
_EMPHASIS_SD = 0.15  # s.d. of log jaw opening of a vowel (stress and emphasis)
_TEMPO_SD = 0.08     # s.d. of log speaking rate between sentences
#: slow postural drift per control (s.d. in control units; 0 = none), first-order, 0.4 Hz corner
_DRIFT_SD = np.array([0.0, 0.05, 0.06, 0.05, 0.0, 0.0, 0.06, 0.05, 0.25, 0.25, 0.3, 0.2, 0.0, 0.0])
_DRIFT_HZ = 0.4
_LATERAL_JAW = 0.3   # s.d. over speakers of the lateral jaw shift per unit of jaw opening
#: token-to-token variability of the lip gestures: a gesture's round, spread, raise, protrude,
#: depress, corner, roll and mentalis targets each times exp(_TOKEN_SD * N(0, 1)), independently
_TOKEN_SD = 0.25
_TOKEN_CONTROLS = np.array([_R, _S, _U, _P, _D, _K, _O, _M])
#: a vowel's emphasis factor (on its jaw opening) also scales its round, spread and protrude targets
_EMPHASIS_CONTROLS = np.array([_J, _R, _S, _P])
#: per-sentence posture of the lip tissue: roll offset N(0, s.d.), mentalis offset |N(0, s.d.)|
_POSTURE_ROLL_SD, _POSTURE_MENTALIS_SD = 0.15, 0.10

#: A second, independently parameterised talker (``SyntheticTalker(**HELD_OUT_TALKER)``):
#: another seed (so another speaker's anatomy), faster speech, sloppier gesture timing,
#: slower articulators, narrower coarticulation, more target jitter and noise. The
#: method's defaults were never tuned on it; tests and docs/RESULTS.md use it as
#: held-out data.
HELD_OUT_TALKER = {"seed": 7, "tempo": 1.15, "timing_sd": 0.12, "dynamics_scale": 1.3, "coarticulation": 0.8,
                   "jitter": 0.06, "noise": 0.25}
#: defaults of the keyword-only generator-variant parameters (left out of the cache key at
#: these values, so the default talker's cache files keep their names)
_VARIANT_DEFAULTS = {"timing_sd": _TIMING_SD, "dynamics_scale": 1.0, "coarticulation": 1.0, "speakers": None,
                     "registration": 0.3, "tissue": False, "kinematics": "classic"}


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
class SyntheticTalker(Estimator):
    """Deterministic synthetic talker producing a phone-aligned 3D lip corpus.

    Parameters
    ----------
    preset : {"small", "default", "paper", "multi"}
        ``"small"``: 75 s, 156 points (tests); ``"default"``: 8 minutes (28,800
        frames at 60 Hz), 600 points; ``"paper"``: 28,833 frames, 4,260 points;
        ``"multi"``: as ``"default"`` spoken by four speakers in turn.
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
        Standard deviation (mm) of capture noise added to each coordinate
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
    speakers : int or None
        Speakers taking turns sentence by sentence, each with their own anatomy
        (:func:`speaker_anatomy`); None: the preset's (1, or 4 for ``"multi"``).
    registration : float, default=0.3
        Size (mm) of the capture's registration error: a spatially smooth, slowly
        varying displacement field over the surface of RMS ``registration`` per
        coordinate (correspondence drift of dense registration), plus residual rigid
        head motion of s.d. ``0.6 * registration`` mm and degrees (0 = perfect).
    tissue : bool, default=False
        The lip tissue's own variation (opt-in): phones drive the ``roll`` and
        ``mentalis`` controls (bilabials press the lips in and raise the chin,
        postalveolars and rounded vowels evert the lips), each token's lip gestures
        vary in size independently (log-normal, s.d. 0.25), a vowel's emphasis scales
        its lip gestures with its jaw opening, and each sentence has its own tissue
        posture. False: ``roll`` and ``mentalis`` stay 0 and the other controls are
        unchanged.
    kinematics : {"classic", "calibrated"}, default="classic"
        How the jaw, upper lip and corners move (:data:`engine.talker.lipmodel.KINEMATICS`).
        ``"calibrated"`` (opt-in) moves them as real speakers' articulograph sensors do:
        the jaw turns on an arc and protrudes on its own (the ``jaw_forward`` control,
        driven by phones: forward for sibilants, dentals and labiodentals, back for
        velars), the upper lip takes a third of the opening, and the corners descend with
        the jaw and narrow and widen whole. ``"classic"``: ``jaw_forward`` stays 0 and the
        frames are those of the classic lip model, bit for bit.
    """

    _parameter_constraints = {
        "preset": [StrOptions(PRESETS)],
        "n_sentences": [Interval(Integral, 1, None, closed="left"), None],
        "duration": [Interval(Real, 3, None, closed="left"), None],  # seconds of speech
        "resolution": [StrOptions(RESOLUTIONS),
                       Condition(lambda r: len(r) == 2 and all(isinstance(v, Integral) and not isinstance(v, bool)
                                                               for v in r) and r[0] >= 3 and r[1] >= 5,
                                 "(rows, cols) with rows >= 3 and cols >= 5", bad=[(2, 5), (3,)]), None],
        "rate": [Interval(Real, 10, 1000, closed="both")],
        "seed": [Interval(Integral, 0, None, closed="left")],
        "noise": [Interval(Real, 0, None, closed="left")],
        "jitter": [Interval(Real, 0, 0.5, closed="both")],
        "tempo": [Interval(Real, 0, None, closed="neither")],
        "timing_sd": [Interval(Real, 0, 0.5, closed="both")],  # a fraction of the phone
        "dynamics_scale": [Interval(Real, 0.25, 4, closed="both")],  # a factor
        "coarticulation": [Interval(Real, 0.25, 4, closed="both")],
        "speakers": [Interval(Integral, 1, 100, closed="both"), None],
        "registration": [Interval(Real, 0, 5, closed="both")],  # mm and degrees
        "tissue": ["boolean"],
        "kinematics": [StrOptions(KINEMATICS)],
    }

    def __init__(self, *, preset: str = "default", n_sentences: int | None = None, duration: float | None = None,
                 resolution: str | None = None, rate: float = 60.0, seed: int = 0, noise: float = 0.2,
                 jitter: float = 0.04, tempo: float = 1.0, timing_sd: float = _TIMING_SD, dynamics_scale: float = 1.0,
                 coarticulation: float = 1.0, speakers: int | None = None, registration: float = 0.3,
                 tissue: bool = False, kinematics: str = "classic") -> None:
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
        self.speakers = speakers
        self.registration = registration
        self.tissue = tissue
        self.kinematics = kinematics

    # -------------------------------------------------------------- validation
    def _validate(self) -> Any:
        validate_params(self)
        dur = PRESETS[self.preset]["duration"] if self.duration is None else float(self.duration)
        res = PRESETS[self.preset]["resolution"] if self.resolution is None else self.resolution
        return dur, res

    # -------------------------------------------------------------- sentences
    def _sentence(self, rng: np.random.Generator, dm: Any, words: Sequence[str], prons: Any,
                  n_words: int) -> Any:
        dm = DurationModel(tempo=self.tempo * math.exp(_TEMPO_SD * rng.standard_normal()))  # this sentence's rate
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

    def _sentences(self, rng: np.random.Generator, total_frames: int) -> list[Any]:
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
            text: list[str]
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
    def _controls(self, rng: np.random.Generator, phones: Sequence[str], durs: Any, n_frames: int,
                  lateral: Any = 0.0) -> np.ndarray:
        """Controls after dynamics for one utterance, ndarray (n_frames, 14)."""
        rate = float(self.rate)
        sub = max(1, math.ceil(240.0 / rate))
        fs = rate * sub
        starts = np.concatenate([[0.0], np.cumsum(durs)[:-1]])
        # lists of the gestures' values, then arrays of them
        cen: Any
        tgt: Any
        alp: Any
        wb: Any
        wa: Any
        vow: Any
        cen, tgt, alp, wb, wa, vow = [], [], [], [], [], []
        for p, s, d in zip(phones, starts, durs):
            gs = phone_gestures(p)
            for g in gs:
                frac = np.broadcast_to(np.asarray(g.frac, dtype=float), (_NC,))
                jit = frac + float(self.timing_sd) * rng.standard_normal()
                cen.append(s + np.clip(jit, np.minimum(frac, 0.0), np.maximum(frac, 1.0)) * d)
                tgt.append(g.target)
                alp.append(g.alpha)
                wb.append([(a * d + b) * self.coarticulation for a, b in g.before])
                wa.append([(a * d + b) * self.coarticulation for a, b in g.after])
                vow.append(p in _VOWELS)
        # the controls that move (the rest stay 0): the default talker's eleven, drawing the same random
        # numbers, plus jaw_forward with the calibrated kinematics and roll and mentalis with
        # the tissue variation; columns of the arrays below are these, in order
        act = np.array(_BASE + ((_F,) if self.kinematics == "calibrated" else ()) + ((_O, _M) if self.tissue else ()))
        col = {int(k): i for i, k in enumerate(act)}
        nc = len(act)
        cen = np.array(cen)[:, act]                                              # (E, nc)
        tgt = np.array(tgt)[:, act]
        if self.tissue:  # token-to-token variability: each lip gesture's size has its own log-normal factor
            tok = [col[k] for k in _TOKEN_CONTROLS]
            tgt[:, tok] *= np.exp(_TOKEN_SD * rng.standard_normal((len(cen), len(tok))))
        tgt += self.jitter * rng.standard_normal((len(cen), nc))
        # stress and emphasis: a vowel's jaw opening (with the tissue variation: and its lip
        # gestures) varies by one log-normal factor
        vow = np.array(vow)
        emph = [col[k] for k in (_EMPHASIS_CONTROLS if self.tissue else [_J])]
        tgt[np.ix_(vow, emph)] *= np.exp(_EMPHASIS_SD * rng.standard_normal(int(vow.sum())))[:, None]
        low = _LOW[act]
        tgt = np.clip(tgt, low, 1.0)                                           # the controls' ranges
        alp, wb, wa = np.array(alp)[:, act], np.array(wb)[:, act], np.array(wa)[:, act]
        omega = 2.146 / (T63[act] * float(self.dynamics_scale))
        lead = 2.0 / omega                                   # group delay of the dynamics
        n_sub = n_frames * sub
        t = np.arange(n_sub) / fs
        # each sample sees the _WINDOW gestures either side of it (sorted by centre)
        order = np.argsort(cen.mean(1), kind="stable")
        cen, tgt, alp, wb, wa = cen[order], tgt[order], alp[order], wb[order], wa[order]
        near = np.searchsorted(cen.mean(1), t)[:, None] + np.arange(-_WINDOW, _WINDOW)[None, :]   # (n, 2W)
        valid = (near >= 0) & (near < len(cen))
        near = np.clip(near, 0, len(cen) - 1)
        tau = t[:, None, None] + lead[None, None, :] - cen[near]                 # (n, 2W, 14)
        w = np.where(tau < 0, wb[near], wa[near])
        dom = alp[near] * np.exp(-(np.abs(tau) / w) ** _SHAPE[act]) * valid[:, :, None]
        u = (dom * tgt[near]).sum(1) / (dom.sum(1) + 1e-12)                    # (n, 14)
        u += 0.02 * rng.standard_normal(u.shape)                               # motor noise
        # slow postural drift (expression, corners, asymmetry, lateral jaw), stationary from the start
        pd = math.exp(-2 * math.pi * _DRIFT_HZ / fs)
        u += _slow_process(rng, n_sub, nc, pd) * _DRIFT_SD[act]
        if self.tissue:  # this sentence's posture of the lip tissue (rolled in or out, chin raised)
            u[:, col[_O]] += _POSTURE_ROLL_SD * rng.standard_normal()
            u[:, col[_M]] += abs(_POSTURE_MENTALIS_SD * rng.standard_normal())
        u[:, col[_X]] += lateral * u[:, col[_J]]                               # this speaker's jaw path
        from scipy.signal import lfilter  # imported on use: a cached talker's start-up does not need it

        p = np.exp(-omega / fs)
        out = np.zeros((len(u), _NC))
        for i, k in enumerate(act):
            b, a = [1 - p[i]], [1.0, -p[i]]
            zi = np.array([p[i]])  # = lfilter_zi(b, a): the state that holds a constant input
            y, _ = lfilter(b, a, u[:, i], zi=zi * u[0, i])
            y, _ = lfilter(b, a, y, zi=zi * u[0, i])
            out[:, k] = y
        return np.clip(out[::sub], _LOW, 1.0)

    # -------------------------------------------------------------- generate
    def generate(self, progress: ProgressFn = None) -> Corpus:
        """Generate the corpus.

        Parameters
        ----------
        progress : callable(stage, done, total) or None

        Returns
        -------
        Corpus
            ``frames`` (n_frames, 3 * n_points) float32 in mm, ``faces``,
            ``point_names``, phone-aligned utterances ``s0001``..., and ``latent``:
            the fourteen controls, ``aperture`` (mm) and ``phase`` (see :func:`gesture_phases`).
        """
        dur, res = self._validate()
        rng = np.random.default_rng(self.seed)
        rate = float(self.rate)
        n_spk = int(PRESETS[self.preset]["speakers"] if self.speakers is None else self.speakers)
        anat = [speaker_anatomy(self.seed, k) for k in range(n_spk)]
        lateral = [float(_LATERAL_JAW * np.random.default_rng([int(self.seed), 2000 + k]).standard_normal())
                   for k in range(n_spk)]
        lips = [LipModel(res, a, kinematics=self.kinematics) for a in anat]
        lip = lips[0]
        total = int(round(dur * rate))
        report(progress, "sentences", 0, 1)
        sents = self._sentences(rng, total)
        report(progress, "sentences", 1, 1)
        who: Any
        ctrls, utts, pos, who = [], [], 0, []
        for k, (ph, d, txt, nf) in enumerate(sents):
            report(progress, "articulation", k, len(sents))
            spk = k % n_spk
            ctrls.append(self._controls(rng, ph, d, nf, lateral[spk]))
            ends = np.cumsum(d)
            ends[-1] = nf / rate
            st = np.concatenate([[0.0], ends[:-1]])
            phones = tuple(PhoneInterval(float(a), float(b), p) for a, b, p in zip(st, ends, ph))
            utts.append(Utterance(f"s{k + 1:04d}", pos, pos + nf, phones, None, txt,
                                  f"spk{spk + 1}" if n_spk > 1 else ""))
            who.append(np.full(nf, spk, np.int16))
            pos += nf
        report(progress, "articulation", len(sents), len(sents))
        C = np.concatenate(ctrls)
        who = np.concatenate(who)
        n = C.shape[0]
        frames = np.empty((n, 3 * lip.n_points), dtype=np.float32)
        aperture = np.empty(n)
        for k, lm in enumerate(lips):
            aperture[who == k] = lm.aperture(C[who == k])
        head = self._head_motion(rng, utts, n)
        field = self._registration_field(rng, utts, n, lip)
        chunk = max(1, 4_000_000 // (3 * lip.n_points))
        for s in range(0, n, chunk):
            report(progress, "geometry", s, n)
            blk = frames[s:s + chunk]
            w = who[s:s + chunk]
            if n_spk == 1:
                lip.deform(C[s:s + chunk], out=blk)
            else:
                for k in np.unique(w):
                    blk[w == k] = lips[k].deform(C[s:s + chunk][w == k])
            if head is not None:  # residual registration error: small rigid motion, P + w x P + t
                P = blk.reshape(len(blk), -1, 3)
                om, tr = head[0][s:s + chunk], head[1][s:s + chunk]
                x, y, z = P[..., 0].copy(), P[..., 1].copy(), P[..., 2].copy()
                for d, (a, b, u, v) in enumerate(((1, 2, z, y), (2, 0, x, z), (0, 1, y, x))):
                    P[..., d] += om[:, a, None] * u - om[:, b, None] * v + tr[:, d, None]
                with one_blas_thread():  # small products: one thread beats two contending ones
                    blk += field[0][s:s + chunk] @ field[1]
            if self.noise > 0:  # uniform capture noise of s.d. `noise` (7x cheaper than normal)
                buf = rng.random(blk.shape, dtype=np.float32)
                buf -= np.float32(0.5)
                buf *= np.float32(self.noise * math.sqrt(12.0))
                blk += buf
        report(progress, "geometry", n, n)
        latent = {name: C[:, k].astype(np.float64) for k, name in enumerate(CONTROL_NAMES)}
        latent["aperture"] = aperture
        bounds = np.array([[u.start, u.stop] for u in utts])
        latent["phase"] = gesture_phases(aperture, bounds)
        self.n_frames_ = int(n)
        self.n_points_ = int(lip.n_points)
        self.n_utterances_ = len(utts)
        self.anatomies_ = anat
        return Corpus(frames=frames, rate=rate, utterances=utts, dims=3, faces=lip.faces,
                      point_names=lip.point_names, point_roles=lip_roles(lip), latent=latent,
                      name=f"synthetic-{self.preset}", axes=LIP_MODEL_AXES)

    def _registration_field(self, rng: np.random.Generator, utts: Sequence[Utterance], n: int,
                            lip: Any) -> tuple[np.ndarray, np.ndarray]:
        """(coefficients (n, K), basis (K, 3 * n_points)) of the smooth registration error:
        products of low-order cosines over the rest surface's x and y (orders 0..3 each,
        amplitude 1 / (1 + a + b)) for each coordinate, coefficients a first-order process
        (1 Hz) per utterance; scaled so the RMS displacement per coordinate is
        ``registration`` mm."""
        V = lip.rest_vertices
        u = (V[:, 0] - V[:, 0].min()) / np.ptp(V[:, 0])
        v = (V[:, 1] - V[:, 1].min()) / np.ptp(V[:, 1])
        basis = []
        for a in range(4):
            for b in range(4):
                phi = np.cos(np.pi * a * u) * np.cos(np.pi * b * v) / (1.0 + a + b)
                for d in range(3):
                    f = np.zeros((len(V), 3))
                    f[:, d] = phi
                    basis.append(f.ravel())
        B = np.array(basis, np.float32)                                  # (48, 3V)
        B *= np.float32(self.registration / math.sqrt((B ** 2).sum() / B.shape[1]))
        rate = float(self.rate)
        ph = math.exp(-2 * math.pi * 1.0 / rate)
        coef = np.empty((n, len(B)), np.float32)
        for utt in utts:
            coef[utt.start:utt.stop] = _slow_process(rng, utt.stop - utt.start, len(B), ph)
        return coef, B

    def _head_motion(self, rng: np.random.Generator, utts: Sequence[Utterance],
                     n: int) -> tuple[np.ndarray, np.ndarray] | None:
        """(rotation vectors (n, 3) in radians, translations (n, 3) in mm) of the residual
        registration error, or None when ``registration`` is 0: per utterance a slow
        first-order process (0.3 Hz) of s.d. ``0.6 * registration`` (mm; degrees)."""
        if not self.registration > 0:
            return None
        rate = float(self.rate)
        ph = math.exp(-2 * math.pi * 0.3 / rate)
        out = np.empty((n, 6), np.float32)
        for u in utts:
            out[u.start:u.stop] = _slow_process(rng, u.stop - u.start, 6, ph)
        out *= np.float32(0.6 * self.registration)
        out[:, :3] *= np.float32(np.pi / 180.0)
        return out[:, :3], out[:, 3:]


_LOW = np.array([-1.0 if n in SIGNED_CONTROLS else 0.0 for n in CONTROL_NAMES])


def _slow_process(rng: np.random.Generator, n: int, k: int, pole: float) -> np.ndarray:
    """(n, k) independent first-order (AR(1)) processes of unit variance with ``pole``,
    stationary from the first sample (its state drawn from the stationary distribution)."""
    from scipy.signal import lfilter

    e = rng.standard_normal((n, k)) * math.sqrt(1 - pole * pole)
    return lfilter([1.0], [1.0, -pole], e, axis=0, zi=rng.standard_normal(k)[None, :] * pole)[0]


def speaker_anatomy(seed: int, speaker: int) -> Anatomy:
    """The lip anatomy of speaker ``speaker`` of the talker with ``seed`` (drawn around the
    adult mean, :meth:`engine.talker.lipmodel.Anatomy.draw`)."""
    return Anatomy.draw(np.random.default_rng([int(seed), 1000 + int(speaker)]))


def lip_roles(lip: Any) -> list[str]:
    """Point roles of a lip surface: the inner-contour midline points are the upper and lower
    lip (their distance is the lip aperture, as :meth:`engine.talker.lipmodel.LipModel.aperture`
    defines it), the inner-contour points at the commissures the corners, the rest lip."""
    roles = ["lip"] * lip.n_points
    up, low = lip.midline
    roles[up], roles[low] = "upper_lip", "lower_lip"
    left = lip.corner_column
    roles[left] = "left_corner"
    roles[lip.cols - 1 - left] = "right_corner"
    return roles
