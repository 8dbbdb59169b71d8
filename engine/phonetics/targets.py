"""Timed key targets for synthesis: from a corpus utterance, phones with durations, a TextGrid or text.

A :class:`TargetSequence` is what every synthesiser consumes: the phone intervals
of the utterance to synthesise (labels in the corpus's own phone set, seconds from
0) and one :class:`Target` per key frame. A target always has a frame and usually
a phone label; *oracle* targets (from a corpus utterance) also carry the F^y point,
its state and the F^x of that frame, which is the paper's Fig. 3 experiment.

Input labels meet the corpus's labels through :func:`engine.phonetics.phonesets.normalize`,
so an ARPAbet corpus (``AH0``) and British-set input (``ax``) match.

Frame convention: frame ``k`` is at time ``k / rate``; a phone's mid-point frame is
``round(mid * rate)`` clipped to the utterance (as :meth:`engine.recordings.corpus.Corpus.time_to_frame`).
"""
from __future__ import annotations

import os
import re
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from engine.recordings.corpus import PhoneInterval

if TYPE_CHECKING:
    from engine.recordings.corpus import Corpus, Utterance

__all__ = [
    "Target", "TargetSequence", "TargetError", "UnknownPhoneError", "PhoneMatcher", "parse_phone_string",
    "stand_in_phone", "resolve_phone",
    "phones_from_durations", "targets_from_phones", "targets_from_textgrid", "targets_from_text",
    "targets_from_utterance", "targets_from_points",
]


class TargetError(ValueError):
    """Targets that cannot be synthesised (colliding frames, out of range, bad syntax)."""


class UnknownPhoneError(TargetError):
    """An input phone the corpus never uses; the message lists the known ones."""


@dataclass(frozen=True)
class Target:
    """One key target.

    Attributes
    ----------
    frame : int
        Frame index in the synthesised trajectory (0-based).
    label : str
        Phone label in the corpus's set ("" if none).
    state : int or None
        Oracle state of the state graph.
    y : ndarray of shape (k,) or None
        Oracle F^y point.
    x : ndarray of shape (m,) or None
        Oracle F^x (shape coordinates) of the frame.
    """

    frame: int
    label: str = ""
    state: int | None = None
    y: np.ndarray | None = field(default=None, compare=False)
    x: np.ndarray | None = field(default=None, compare=False)


@dataclass
class TargetSequence:
    """Timed targets and the phone intervals they come from.

    Attributes
    ----------
    targets : tuple of Target
        Strictly increasing frames.
    phones : tuple of PhoneInterval
        Phone intervals (corpus labels), seconds from the start.
    n_frames : int
        Frames in the trajectory to synthesise.
    rate : float
        Frame rate (Hz).
    source : str
        Where the targets came from (for messages).
    utterance : str or None
        Corpus utterance id for oracle targets.
    """

    targets: tuple
    phones: tuple
    n_frames: int
    rate: float
    source: str = ""
    utterance: str | None = None

    @property
    def frames(self) -> np.ndarray:
        return np.array([t.frame for t in self.targets], dtype=np.int64)

    @property
    def labels(self) -> list[str]:
        return [t.label for t in self.targets]

    @property
    def has_oracle(self) -> bool:
        return bool(self.targets) and all(t.state is not None or t.y is not None for t in self.targets)

    def phones_only(self) -> TargetSequence:
        """The same targets with the oracle (state, F^y, F^x) removed: labels and times only."""
        return replace(self, targets=tuple(Target(t.frame, t.label) for t in self.targets))


# ------------------------------------------------------------------ phone labels
def _normalize(label: str, phoneset: str | None = None) -> str | None:
    """Canonical phone of ``label``, or None when no phone set knows it."""
    from engine.phonetics.phonesets import UNKNOWN, normalize

    c = normalize(label, strict=False, phoneset=phoneset)
    if c == UNKNOWN and phoneset is not None:
        c = normalize(label, strict=False)
    return None if c == UNKNOWN else c


class PhoneMatcher:
    """Map input phone labels onto a corpus's own labels through phone-set normalisation.

    Parameters
    ----------
    labels : sequence of str
        The corpus's phone labels, one per phone instance (the most frequent corpus
        label wins when several normalise to the same phone).
    name : str
        Corpus name for messages.
    """

    def __init__(self, labels: Iterable[str], name: str = "the corpus") -> None:
        counts = Counter(str(s) for s in labels)
        self.name = name
        self.known = sorted(counts)
        self._exact = set(counts)
        self._map: dict[str, str] = {}
        from engine.phonetics.phonesets import detect_phoneset

        self.phoneset = detect_phoneset(list(counts))  # the corpus's own set decides its ambiguous symbols
        for lab, _ in counts.most_common():
            key = _normalize(lab, self.phoneset)
            if key is not None:
                self._map.setdefault(key, lab)

    @classmethod
    def for_corpus(cls, corpus: Corpus) -> PhoneMatcher:
        return cls([p.label for u in corpus.utterances for p in u.phones], corpus.name)

    def match(self, label: str, where: str = "") -> str:
        """The corpus label for ``label``; :class:`UnknownPhoneError` if the corpus lacks it."""
        if label in self._exact:
            return label
        key = _normalize(label)
        if key is not None and key in self._map:
            return self._map[key]
        at = f" ({where})" if where else ""
        if not self.known:
            raise UnknownPhoneError(
                f"phone {label!r}{at}: {self.name} has no phone labels, so phone targets cannot be placed; use "
                "its utterances (kinematic landmarks) or manifold states as targets (lipspace synthesize "
                "--utterance ID / --states S,S,...)")
        raise UnknownPhoneError(
            f"phone {label!r}{at} does not occur in {self.name}; known phones: {' '.join(self.known)}")


def stand_in_phone(label: str, known: Iterable[str]) -> str | None:
    """The known phone closest to ``label`` in articulation, for a phone the training corpus lacks.

    Tried in order: same lip-reading class, place and manner; same place and manner; same
    manner and lip-reading class; same place and lip-reading class; same broad class;
    same lip-reading class. Among
    several, the first in ``known``'s order (pass them most frequent first). Returns
    None when nothing shares even the lip-reading class (or ``label`` is unknown).
    """
    from engine.phonetics.phonesets import phone_info

    me = phone_info(label, strict=False)
    if me is None:
        return None
    infos = [(k, phone_info(k, strict=False)) for k in known]
    infos = [(k, i) for k, i in infos if i is not None and i.canonical != me.canonical]
    keys = (lambda i: (i.lipreading, i.place, i.manner), lambda i: (i.place, i.manner),
            lambda i: (i.manner, i.lipreading), lambda i: (i.place, i.lipreading), lambda i: i.broad_class,
            lambda i: i.lipreading)
    for key in keys:
        for k, i in infos:
            if key(i) == key(me):
                return k
    return None


def resolve_phone(label: str, known: Sequence[str], warnings: list[str] | None, what: str) -> str:
    """``label`` if in ``known``, else a stand-in phone (:func:`stand_in_phone`, noted in ``warnings``),
    else a ValueError listing the known; ``what`` names what the phone lacks ("instances", ...)."""
    if label in known:
        return label
    if not str(label).strip():  # a target given as a state (or clicked) has no phone to look up
        raise ValueError("a target without a phone label (given as a state) cannot be synthesised by a method "
                         "that works from phone labels; use a method that works from states (manifold, viterbi, "
                         "sv-hermite)")
    sub = stand_in_phone(label, known)
    if sub is None:
        raise ValueError(f"phone {label!r} has no {what} in the training corpus and no phone of its class stands "
                         f"in; known phones: {', '.join(sorted(known))}")
    if warnings is not None:
        warnings.append(f"phone {label!r} is not in the training corpus; {sub!r} stands in for it")
    return sub


# ------------------------------------------------------------------ parsing
_NUM = re.compile(r"^[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$")


def parse_phone_string(text: str) -> list[tuple[str, float]]:
    """Parse ``"p 0.08 ax 0.05 ..."`` (label, duration in seconds, repeated) into pairs.

    Commas and semicolons may separate pairs. Raises :class:`TargetError` naming the
    token at fault.
    """
    toks = [t for t in re.split(r"[\s,;]+", text.strip()) if t]
    if not toks:
        raise TargetError("empty phone string; expected 'label duration' pairs, e.g. 'p 0.08 ax 0.05'")
    if len(toks) % 2:
        raise TargetError(f"phone string has {len(toks)} tokens, not label/duration pairs (last: {toks[-1]!r}); "
                          "expected e.g. 'p 0.08 ax 0.05'")
    out = []
    for i in range(0, len(toks), 2):
        lab, dur = toks[i], toks[i + 1]
        if not _NUM.match(dur):
            raise TargetError(f"phone {i // 2} ({lab!r}): duration {dur!r} is not a number of seconds; "
                              "expected 'label duration' pairs, e.g. 'p 0.08 ax 0.05'")
        if _NUM.match(lab):
            raise TargetError(f"phone {i // 2}: label {lab!r} is a number; expected 'label duration' pairs")
        out.append((lab, float(dur)))
    return out


def phones_from_durations(pairs: Iterable[tuple[str, float]]) -> tuple[PhoneInterval, ...]:
    """Consecutive :class:`PhoneInterval` from (label, duration s) pairs, starting at 0."""
    out, t = [], 0.0
    for i, item in enumerate(pairs):
        try:
            lab, dur = item
            dur = float(dur)
        except (TypeError, ValueError):
            raise TargetError(f"phone {i}: expected (label, duration), got {item!r}") from None
        if not np.isfinite(dur) or dur <= 0:
            raise TargetError(f"phone {i} ({lab!r}): duration {dur} s must be > 0")
        out.append(PhoneInterval(t, t + dur, str(lab)))
        t += dur
    if not out:
        raise TargetError("no phones given")
    return tuple(out)


def _as_intervals(phones: Any) -> tuple[PhoneInterval, ...]:
    if isinstance(phones, str):
        return phones_from_durations(parse_phone_string(phones))
    phones = list(phones)
    if phones and all(isinstance(p, PhoneInterval) for p in phones):
        out = tuple(phones)
        for i, p in enumerate(out):
            if p.end <= p.start:
                raise TargetError(f"phone {i} ({p.label!r}) has no duration ({p.start:.4f}-{p.end:.4f} s)")
            if i and p.start < out[i - 1].end - 1e-9:
                raise TargetError(f"phone {i} ({p.label!r}) starts at {p.start:.4f} s before phone {i - 1} ends "
                                  f"at {out[i - 1].end:.4f} s")
        if not out:
            raise TargetError("no phones given")
        return out
    return phones_from_durations(phones)


def _frame_of(t: float, rate: float, n: int) -> int:
    return int(np.clip(int(round(t * rate)), 0, n - 1))


def _mid_targets(phones: Sequence[PhoneInterval], rate: float, n_frames: int, on_collision: str,
                 source: str) -> tuple[list[int], list[int]]:
    """Mid-point frames of ``phones``; resolve or reject collisions."""
    frames = [_frame_of(p.mid, rate, n_frames) for p in phones]
    keep: list[int] = []
    for i, f in enumerate(frames):
        if keep and f <= frames[keep[-1]]:
            j = keep[-1]
            if on_collision == "error":
                raise TargetError(
                    f"{source}: phones {j} ({phones[j].label!r}) and {i} ({phones[i].label!r}) have their "
                    f"mid-points on the same frame {f} at {rate:g} Hz (a zero-length gap); give them durations "
                    f"of at least {1.0 / rate:.3f} s")
            continue  # "merge": the earlier target stands for both
        keep.append(i)
    return keep, frames


def _corpus_of(obj: Any) -> Corpus:
    """A Corpus from a manifold (its training corpus) or a corpus."""
    return getattr(obj, "corpus_", obj)


def _labelled(phones: Iterable[PhoneInterval], matcher: PhoneMatcher, source: str) -> tuple[PhoneInterval, ...]:
    return tuple(PhoneInterval(p.start, p.end, matcher.match(p.label, f"{source}, phone {i}"))
                 for i, p in enumerate(phones))


def targets_from_phones(manifold: Any, phones: Any, *, rate: float | None = None, on_collision: str = "error",
                        source: str = "phones") -> TargetSequence:
    """Phone mid-point targets (labels only) from phones with durations.

    Parameters
    ----------
    manifold : Manifold or Corpus
        Gives the phone set (its corpus's labels) and the frame rate.
    phones : str, sequence of (label, duration) or sequence of PhoneInterval
        ``"p 0.08 ax 0.05 ..."``, pairs, or intervals in seconds.
    rate : float, optional
        Frame rate; default the corpus's.
    on_collision : {"error", "merge"}
        Two mid-points on one frame: raise, or keep the earlier target only.
    """
    if on_collision not in ("error", "merge"):
        raise ValueError(f"on_collision must be 'error' or 'merge', got {on_collision!r}")
    corpus = _corpus_of(manifold)
    rate = float(rate or corpus.rate)
    ph = _labelled(_as_intervals(phones), PhoneMatcher.for_corpus(corpus), source)
    n = max(1, int(round(ph[-1].end * rate)))
    keep, frames = _mid_targets(ph, rate, n, on_collision, source)
    return TargetSequence(tuple(Target(frames[i], ph[i].label) for i in keep), ph, n, rate, source)


def targets_from_textgrid(manifold: Any, path: str | os.PathLike[str], *, tier: str | None = None,
                          on_collision: str = "error") -> TargetSequence:
    """Targets from a Praat TextGrid (or HTK/MOCHA ``.lab``) phone alignment, via :func:`engine.io.read_alignment`."""
    from engine.io import read_alignment

    phones = read_alignment(path, tier=tier)
    if not phones:
        raise TargetError(f"{path}: the alignment holds no phones")
    t0 = phones[0].start
    shifted = [PhoneInterval(p.start - t0, p.end - t0, p.label) for p in phones]
    return targets_from_phones(manifold, shifted, on_collision=on_collision, source=str(path))


def targets_from_text(manifold: Any, text: str, *, duration_model: Any = None, pauses: bool | None = None,
                      on_collision: str = "error") -> TargetSequence:
    """Targets from English text: :func:`engine.phonetics.phones.pronounce` and a
    :class:`~engine.phonetics.phones.DurationModel`.

    ``pauses=None`` brackets the text with the pause phone when the corpus has one.
    """
    from engine.phonetics.phones import PAUSE, DurationModel, pronounce

    corpus = _corpus_of(manifold)
    matcher = PhoneMatcher.for_corpus(corpus)
    if pauses is None:
        try:
            matcher.match(PAUSE)
            pauses = True
        except UnknownPhoneError:
            pauses = False
    labels = pronounce(text)
    if not labels:  # before the pauses: punctuation alone is not silence to synthesise
        raise TargetError(f"no words in the text {text[:60]!r}; give the words to synthesise")
    if pauses:
        labels = [PAUSE, *labels, PAUSE]
    dm = duration_model or DurationModel()
    durs = dm.durations(labels)
    return targets_from_phones(manifold, list(zip(labels, durs)), on_collision=on_collision,
                               source=f"text {text[:40]!r}")


def _match_or_keep(matcher: PhoneMatcher, label: str) -> str:
    try:
        return matcher.match(label)
    except UnknownPhoneError:
        return label


def targets_from_utterance(manifold: Any, utterance: str | Utterance, *, corpus: Corpus | None = None,
                           key_frames: Sequence[int] | str | None = None,
                           on_collision: str = "error") -> TargetSequence:
    """Oracle targets from a corpus utterance: its own phone mid-points (the paper's Fig. 3).

    An utterance without phones uses its kinematic landmarks (:mod:`engine.recordings.kinematics`:
    aperture maxima and minima, peak opening and closing velocity) as targets, labelled
    with their kind, when the corpus names upper and lower lip points.

    Parameters
    ----------
    manifold : Manifold
        Fitted.
    utterance : str or Utterance
        Utterance id.
    corpus : Corpus, optional
        Where the utterance lives when it is not in the manifold's training corpus (a
        held-out utterance). Its frames are projected out-of-sample
        (shape -> dynamics -> embedding), since they are not in the training set.
    key_frames : sequence of int, optional
        Target frames (0-based within the utterance) instead of the phone mid-points;
        a target's label is the phone covering its frame.
    on_collision : {"error", "merge"}

    Returns
    -------
    TargetSequence
        Targets carry ``state``, ``y`` (F^y) and ``x`` (F^x) of their frame.
    """
    own = corpus is None
    c: Any = manifold.corpus_ if own else corpus
    uid = getattr(utterance, "id", utterance)
    try:
        u = c.utterance(uid)
    except KeyError:
        ids = [x.id for x in c.utterances]
        raise TargetError(f"no utterance {uid!r} in {c.name} ({len(ids)} utterances: "
                          f"{', '.join(ids[:8])}{' ...' if len(ids) > 8 else ''})") from None
    if own:
        Y = np.asarray(manifold.Fy_[u.start:u.stop])
        X = np.asarray(manifold.Fx_[u.start:u.stop])
    else:
        F = c.frames[u.start:u.stop]
        Y = manifold.project(F)
        X = manifold.shape_.transform(F)
    n = u.n_frames
    source = f"utterance {u.id!r}"
    phones = u.phones
    if phones and not own:  # held-out: use training labels where they match, keep the rest as given
        matcher = PhoneMatcher.for_corpus(manifold.corpus_)
        phones = tuple(PhoneInterval(p.start, p.end, _match_or_keep(matcher, p.label)) for p in phones)
    if key_frames is None and not phones:
        from engine.recordings.kinematics import lip_aperture, with_kinematic_labels

        one = c.subset([u.id])
        if lip_aperture(one) is None:
            raise TargetError(f"{source} has no phone alignment and {c.name} names no upper/lower lip points for "
                              "kinematic landmarks; give key frames (lipspace synthesize --key-frames F,F,...)")
        phones = with_kinematic_labels(one).utterances[0].phones  # aperture extrema and peak velocities
        source += " (kinematic landmarks: it has no phone alignment)"
        if not phones:
            raise TargetError(f"{source}: no kinematic landmarks found (the lips hardly move); give key frames "
                              "(--key-frames F,F,...)")
    if key_frames is None:
        ph = phones
        keep, frames = _mid_targets(ph, c.rate, n, on_collision, source)
        items = [(frames[i], ph[i].label) for i in keep]
    else:
        try:
            kf = np.asarray(key_frames, dtype=np.int64).reshape(-1)
        except (OverflowError, TypeError, ValueError):  # 10**30 does not fit a frame index
            raise TargetError(f"{source}: key frames {list(key_frames)[:5]} are not frame indices; expected whole "
                              f"numbers from 0 to {n - 1}") from None
        if kf.size == 0:
            raise TargetError(f"{source}: no key frames given")
        bad = kf[(kf < 0) | (kf >= n)]
        if bad.size:
            raise TargetError(f"{source}: key frame {int(bad[0])} is outside the utterance's frames 0..{n - 1}")
        if np.any(np.diff(kf) <= 0):
            raise TargetError(f"{source}: key frames must be strictly increasing, got {kf.tolist()[:10]}")
        ph = phones
        items = []
        for f in kf:
            t = f / c.rate
            lab = next((p.label for p in ph if p.start <= t < p.end), "")
            items.append((int(f), lab))
    d = int(manifold.states_.centroids_.shape[1])
    fr = np.array([f for f, _ in items], dtype=np.int64)
    st = manifold.states_.predict(np.asarray(Y[fr, :d], dtype=np.float64))
    targets = tuple(Target(int(f), lab, int(s), np.asarray(Y[f], dtype=np.float64), np.asarray(X[f], dtype=np.float64))
                    for (f, lab), s in zip(items, st))
    return TargetSequence(targets, tuple(ph), n, c.rate, source, u.id)


def targets_from_points(manifold: Any, items: Iterable[tuple[int, Any]], *, n_frames: int,
                        rate: float | None = None) -> TargetSequence:
    """Targets at explicit frames: ``items`` = sequence of (frame, state) or (frame, F^y point).

    Raises :class:`TargetError` for a frame outside ``0..n_frames-1``, frames out of order
    or repeated, or a state outside the state graph.
    """
    K = int(manifold.states_.centroids_.shape[0])
    rate = float(rate or manifold.corpus_.rate)
    out: list[Target] = []
    for i, (f, what) in enumerate(items):
        f = int(f)
        if not 0 <= f < n_frames:
            raise TargetError(f"target {i}: frame {f} is outside 0..{n_frames - 1}")
        if out and f <= out[-1].frame:
            raise TargetError(f"target {i}: frame {f} does not follow target {i - 1} at frame {out[-1].frame} "
                              "(a gap needs at least one frame)")
        if np.ndim(what) == 0:
            s = int(what)
            if not 0 <= s < K:
                raise TargetError(f"target {i}: state {s} is outside the state graph's 0..{K - 1}")
            out.append(Target(f, "", s))
        else:
            out.append(Target(f, "", None, np.asarray(what, dtype=np.float64).reshape(-1)))
    if not out:
        raise TargetError("no targets given")
    return TargetSequence(tuple(out), (), int(n_frames), rate, "points")
