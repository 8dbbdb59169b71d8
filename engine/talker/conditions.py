"""Conditions spoken by the synthetic talker, with a known difference in one part of the movement.

Each drawn sentence is said several times -- once per condition, repetition and speaker
when the design is paired (the same sentence in each condition), or in one condition only
when it is not -- each token with its own articulation (timing, targets, noise, head
motion) and its own speaking rate. Each condition's tokens are then changed by its
*effect* acting on the talker's articulatory controls (:data:`EFFECTS`):

``bilabial_release``
    After the closure of every /p/, /b/ and /m/, the jaw opens further: ``size`` (control
    units, the jaw's range being 0-1) times a smooth bump that rises from the closure peak
    (30 % into /p b/, 75 % into /m/, where the talker's closure gestures peak) to its
    greatest height halfway from there to the phone's end -- the middle of the release,
    which for /p b/ holds the phone's mid-point -- and falls back to zero at the middle of
    the next phone.
    The lips stay closed while the closure holds (the lip model's closure overrides the
    jaw), so the lips open wider on the release and nowhere else.
``slow_closing``
    Every closing movement of the jaw (falling) and of the bilabial closure (rising) lags
    behind its target with a first-order time constant of ``size`` seconds; opening follows
    the target as before.
``none``
    No difference: the two conditions differ only by chance (for calibration).

The change is applied as a geometric difference: a changed token's frames get ``deform(controls
after) - deform(controls before)`` of the speaker's own lip model, so capture noise, head
motion and registration error stay those of the token. ``effect_mm`` gives, per frame, how
far the effect moved the lips (RMS over the points, mm): where the difference is.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from engine.talker.gestures import gesture_phases
from engine.talker.lipmodel import CONTROL_NAMES, LipModel
from engine.talker.synthetic_talker import PRESETS, SyntheticTalker

__all__ = ["EFFECTS", "DEFAULT_SIZE", "ConditionCorpus", "condition_corpus", "apply_effect"]

#: the known differences condition b can have
EFFECTS = ("none", "bilabial_release", "slow_closing")
#: each effect's default size (jaw control units; seconds)
DEFAULT_SIZE = {"none": 0.0, "bilabial_release": 0.5, "slow_closing": 0.1}
#: s.d. of a token's log speaking rate around its sentence's
TOKEN_TEMPO_SD = 0.06
_JAW, _CLOSURE = CONTROL_NAMES.index("jaw"), CONTROL_NAMES.index("closure")
#: bilabials and where in the phone their closure peaks (engine.talker.synthetic's gestures)
_CLOSURE_PEAK = {"p": 0.3, "b": 0.3, "m": 0.75}


@dataclass
class ConditionCorpus:
    """A corpus of several conditions and where they differ.

    Attributes
    ----------
    corpus : engine.recordings.corpus.Corpus
    fields : dict of str to ndarray of str, one per utterance
        ``condition`` (the level names), ``text`` (the sentence), ``speaker``, ``repetition``.
    effect_mm : ndarray of shape (n_frames,)
        How far the effect moved each frame's lips (RMS over the points, mm; 0 where none acts).
    effects : dict of str to (str, float)
        Each condition's effect and size.
    """

    corpus: object
    fields: dict
    effect_mm: np.ndarray
    effects: dict

    @property
    def levels(self) -> tuple:
        return tuple(self.effects)


class _ScriptedTalker(SyntheticTalker):
    """The synthetic talker saying each drawn sentence ``tokens`` times, each token at its own rate."""

    tokens = 1

    def _sentences(self, rng, total_frames):
        out = []
        for phones, durs, text, _nf in super()._sentences(rng, total_frames):
            for _ in range(self.tokens):
                d = np.asarray(durs, np.float64) * math.exp(TOKEN_TEMPO_SD * rng.standard_normal())
                out.append((phones, d, text, max(2, int(round(d.sum() * float(self.rate))))))
        return out


def _bump(t, t0, tp, t1) -> np.ndarray:
    """0 before t0, rising as sin^2 to 1 at tp, falling as sin^2 to 0 at t1."""
    out = np.zeros_like(t)
    up = (t >= t0) & (t <= tp)
    if tp > t0:
        out[up] = np.sin(0.5 * np.pi * (t[up] - t0) / (tp - t0)) ** 2
    down = (t > tp) & (t <= t1)
    if t1 > tp:
        out[down] = np.sin(0.5 * np.pi * (t1 - t[down]) / (t1 - tp)) ** 2
    return out


def _lagged(u, a, closing_up: bool) -> np.ndarray:
    """``u`` with its closing movements (rising if ``closing_up``, else falling) lagging (first order, gain a)."""
    y = np.empty_like(u)
    y[0] = u[0]
    for i in range(1, len(u)):
        closing = u[i] > y[i - 1] if closing_up else u[i] < y[i - 1]
        y[i] = y[i - 1] + a * (u[i] - y[i - 1]) if closing else u[i]
    return y


def apply_effect(controls, phones, rate: float, effect: str, size: float) -> np.ndarray:
    """The controls of one utterance (n, 14) after ``effect`` of ``size`` (module docstring)."""
    if effect not in EFFECTS:
        raise ValueError(f"effect={effect!r}; expected one of {EFFECTS}")
    if not (np.isfinite(size) and size >= 0):
        raise ValueError(f"size={size!r}: must be >= 0")
    C = np.array(controls, dtype=np.float64)
    if effect == "none" or size == 0:
        return C
    t = np.arange(len(C)) / float(rate)
    if effect == "bilabial_release":
        bump = np.zeros(len(C))
        for k, p in enumerate(phones):
            if p.label not in _CLOSURE_PEAK:
                continue
            t0 = p.start + _CLOSURE_PEAK[p.label] * (p.end - p.start)
            tp = 0.5 * (t0 + p.end)
            t1 = p.end + 0.5 * (phones[k + 1].end - phones[k + 1].start) if k + 1 < len(phones) else p.end
            bump = np.maximum(bump, _bump(t, t0, tp, t1))
        C[:, _JAW] = np.minimum(C[:, _JAW] + size * bump, 1.0)
        return C
    a = 1.0 - math.exp(-1.0 / (size * float(rate)))
    C[:, _JAW] = _lagged(C[:, _JAW], a, closing_up=False)
    C[:, _CLOSURE] = _lagged(C[:, _CLOSURE], a, closing_up=True)
    return C


def _effects(conditions) -> dict:
    out = {}
    for level, spec in dict(conditions).items():
        effect, size = (spec, None) if isinstance(spec, str) else tuple(spec)
        size = DEFAULT_SIZE.get(effect, 0.0) if size is None else float(size)
        apply_effect(np.zeros((1, len(CONTROL_NAMES))), (), 60.0, effect, size)  # validates effect and size
        out[str(level)] = (effect, size)
    if len(out) < 2:
        raise ValueError(f"conditions={conditions!r}: give at least two conditions")
    return out


def condition_corpus(*, conditions=None, n_texts: int = 8, repetitions: int = 1, speakers: int = 1,
                     paired: bool = True, preset: str = "small", seed: int = 0, progress=None,
                     **talker_params) -> ConditionCorpus:
    """Generate conditions of the synthetic talker, each with its effect (module docstring).

    Parameters
    ----------
    conditions : mapping of str to effect name or (effect, size), optional
        The conditions in order, each with the effect its tokens get (a size of None takes
        :data:`DEFAULT_SIZE`). Default ``{"a": "none", "b": "bilabial_release"}``.
    n_texts : int
        Sentences drawn. Paired: each is said in every condition; unpaired: the sentences go
        to the conditions in turn.
    repetitions : int
        Tokens of each sentence per condition and speaker.
    speakers : int
        Speakers, each with their own anatomy, saying every token of the design.
    paired : bool
    preset : str
        The talker's preset (its lip-surface resolution; ``"small"`` for tests).
    seed : int
    **talker_params
        Further :class:`engine.talker.synthetic.SyntheticTalker` parameters.

    Returns
    -------
    ConditionCorpus
    """
    effects = _effects({"a": "none", "b": "bilabial_release"} if conditions is None else conditions)
    levels = list(effects)
    for name, v, lo in (("n_texts", n_texts, 1), ("repetitions", repetitions, 1), ("speakers", speakers, 1)):
        if int(v) != v or v < lo:
            raise ValueError(f"{name}={v!r}: must be an integer >= {lo}")
    per_text = (len(levels) if paired else 1) * repetitions * speakers
    talker = _ScriptedTalker(preset=preset, n_sentences=n_texts if paired else len(levels) * n_texts, seed=seed,
                             speakers=speakers, **talker_params)
    talker.tokens = per_text
    corpus = talker.generate(progress=progress)
    n_utt = len(corpus.utterances)
    k = np.arange(n_utt)
    text_no, within = k // per_text, k % per_text
    spk, rest = within % speakers, within // speakers
    rep = rest % repetitions
    cond = rest // repetitions if paired else text_no % len(levels)
    fields = {"condition": np.asarray([levels[c] for c in cond], dtype=str),
              "text": np.asarray([u.text for u in corpus.utterances], dtype=str),
              "speaker": np.asarray([u.speaker or "spk1" for u in corpus.utterances], dtype=str),
              "repetition": np.asarray([str(r + 1) for r in rep], dtype=str)}
    effect_mm = np.zeros(corpus.n_frames)
    res = talker.resolution or PRESETS[preset]["resolution"]
    lips = [LipModel(res, a, kinematics=talker.kinematics) for a in talker.anatomies_]
    C = np.column_stack([corpus.latent[n] for n in CONTROL_NAMES])
    changed = False
    for i in range(n_utt):
        effect, size = effects[levels[cond[i]]]
        if effect == "none" or size == 0:
            continue
        u = corpus.utterances[i]
        lip = lips[int(spk[i])]
        before = C[u.start:u.stop]
        after = apply_effect(before, u.phones, corpus.rate, effect, size)
        delta = lip.deform(after) - lip.deform(before)
        corpus.frames[u.start:u.stop] += delta.astype(np.float32)
        effect_mm[u.start:u.stop] = np.sqrt((delta.reshape(len(delta), -1, 3) ** 2).sum(-1).mean(-1))
        C[u.start:u.stop] = after
        corpus.latent["aperture"][u.start:u.stop] = lip.aperture(after)
        changed = True
    if changed:
        for j, name in enumerate(CONTROL_NAMES):
            corpus.latent[name] = C[:, j].copy()
        corpus.latent["phase"] = gesture_phases(corpus.latent["aperture"], corpus.bounds)
    corpus.name = f"synthetic-{preset}-conditions"
    said = ", ".join(f"{lv}: {e}" + (f" {s:g}" if e != "none" else "") for lv, (e, s) in effects.items())
    corpus.history.append(f"conditions ({said}), {'paired' if paired else 'unpaired'} by text, {n_texts} texts x "
                          f"{repetitions} repetition(s) x {speakers} speaker(s)")
    return ConditionCorpus(corpus, fields, effect_mm, effects)
