"""Registration: head motion, recording offsets and speakers removed before the shape space.

Three things make lip coordinates differ that are not lip movement:

* **head motion** within a recording — removed by rigid (Procrustes / Kabsch)
  alignment of every frame's *reference* (head) sensors to their mean configuration,
  the same rotation and translation applied to every point (:func:`register`,
  ``method="rigid"``), when the corpus has at least three reference sensors;
* **offsets between recordings** (the head sits elsewhere in the field each time) —
  without reference sensors, each utterance (``"utterance"``) or each speaker
  (``"speaker"``) is translated so that its mean lip centroid is at the corpus mean;
  an explicit choice the corpus records in ``Corpus.registration``;
* **speakers** — different anatomy and sensor placement: :func:`normalise_speakers`
  subtracts each speaker's mean frame (optionally divides by its spread) and adds the
  pooled mean back, so the shape space models movement, not who is speaking
  (``Manifold(speaker_normalisation=...)``).

:func:`explain_split` names the cause when the state graph falls apart along speakers
or recordings; :class:`engine.manifold.model.Manifold` warns with it.
"""
from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from engine.recordings.corpus import Corpus, CorpusError, CorpusWarning

__all__ = ["register", "normalise_speakers", "explain_split", "warn_if_split", "REGISTRATION_METHODS", "SPEAKER_MODES",
           "RegistrationSplitWarning"]

REGISTRATION_METHODS = ("auto", "rigid", "utterance", "speaker", "none")
SPEAKER_MODES = ("auto", "mean", "mean+scale", "none")
#: a component "belongs" to a speaker / recording when this fraction of its frames comes from it
_DOMINANT = 0.9


class RegistrationSplitWarning(CorpusWarning):
    """The state graph splits along speakers or recordings (a registration / normalisation problem)."""


def _points(corpus):
    if corpus.dims != 3:
        raise CorpusError(f"{corpus.name}: rigid registration needs 3-D points, the corpus is {corpus.dims}-D")
    return corpus.frames.reshape(corpus.n_frames, -1, 3).astype(np.float64)


def _kabsch(A, B):
    """Rotations R (n, 3, 3) and translations t (n, 3) with R @ A[i] + t ~ B, for A (n, k, 3), B (k, 3)."""
    ca = A.mean(axis=1, keepdims=True)
    cb = B.mean(axis=0)
    H = np.einsum("nki,kj->nij", A - ca, B - cb)
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(np.einsum("nij,njk->nik", U, Vt)))
    D = np.broadcast_to(np.eye(3), H.shape).copy()
    D[:, 2, 2] = d
    R = np.einsum("nji,njk,nlk->nil", Vt, D, U)  # V D U^T
    t = cb - np.einsum("nij,nj->ni", R, ca[:, 0])
    return R, t


def register(corpus: Corpus, *, method: str = "auto", drop_reference: bool = True) -> Corpus:
    """Remove head motion / recording offsets; the corpus records what was done.

    Parameters
    ----------
    corpus : Corpus
    method : {"auto", "rigid", "utterance", "speaker", "none"}
        ``rigid``: per-frame Procrustes alignment of the reference sensors (role
        ``reference``, at least 3) to their mean configuration; ``utterance`` /
        ``speaker``: translate each utterance / speaker so that its mean lip centroid is
        the corpus's; ``auto``: nothing when the corpus is already registered, rigid with 3
        or more reference sensors, else utterance centring when there are several
        utterances, else none.
    drop_reference : bool, default=True
        After rigid registration, leave the reference sensors out (they no longer move).

    Returns
    -------
    Corpus
        A new corpus; ``registration`` says what was done, ``history`` gets a line.
    """
    if method not in REGISTRATION_METHODS:
        raise ValueError(f"registration method {method!r}; expected one of {', '.join(REGISTRATION_METHODS)}")
    ref = corpus.role_points("reference")
    if method == "auto" and corpus.registration:
        return corpus  # already registered (e.g. a native corpus file imported again)
    if method == "auto":
        method = "rigid" if ref.size >= 3 else ("utterance" if len(corpus.utterances) > 1 else "none")
    if method == "none":
        return corpus
    P = _points(corpus) if method == "rigid" else None
    if method == "rigid":
        assert P is not None
        if ref.size < 3:
            names = corpus.point_names or []
            raise CorpusError(f"{corpus.name}: rigid registration needs at least 3 reference sensors, the corpus has "
                              f"{ref.size} ({', '.join(names[i] for i in ref) or 'none'}); mark head sensors with "
                              "the role 'reference' in the layout, or choose method='utterance' or 'speaker'")
        A = P[:, ref]
        template = A[0] - A[0].mean(axis=0)
        for _ in range(2):  # template = mean aligned reference configuration
            R, t = _kabsch(A, template)
            aligned = np.einsum("nij,nkj->nki", R, A) + t[:, None]
            template = aligned.mean(axis=0)
            template -= template.mean(axis=0)
        R, t = _kabsch(A, template)
        resid = np.einsum("nij,nkj->nki", R, A) + t[:, None] - template
        rms = float(np.sqrt((resid ** 2).sum(axis=2).mean()))
        Q = np.einsum("nij,nkj->nki", R, P) + t[:, None]
        names = corpus.point_names or [f"p{i}" for i in range(corpus.n_points)]
        keep = [i for i in range(corpus.n_points) if not (drop_reference and i in set(ref.tolist()))]
        if not keep:
            raise CorpusError(f"{corpus.name}: every point is a reference sensor; nothing is left to model")
        desc = (f"rigid (Procrustes) to reference sensors {', '.join(names[i] for i in ref)}, "
                f"residual {rms:.3g} {corpus.unit_label} rms{', reference sensors dropped' if drop_reference else ''}")
        roles = [corpus.point_roles[i] for i in keep] if corpus.point_roles is not None else None
        from engine.recordings.signals.quality import with_points

        return replace(corpus, frames=Q[:, keep].reshape(corpus.n_frames, -1).astype(np.float32),
                       point_names=[names[i] for i in keep] if corpus.point_names is not None else None,
                       point_roles=roles, faces=None if len(keep) < corpus.n_points else corpus.faces,
                       latent=with_points(corpus.latent, keep, corpus.n_points),
                       registration=desc, history=list(corpus.history) + [f"registration: {desc}"])
    F = corpus.frames.astype(np.float64).reshape(corpus.n_frames, -1, corpus.dims)
    from engine.recordings.layouts import LIP_ROLES

    lips = [i for i, r in enumerate(corpus.point_roles or []) if r in LIP_ROLES] or list(range(corpus.n_points))
    centroid = F[:, lips].mean(axis=1)  # (N, dims)
    target = centroid.mean(axis=0)
    if method == "utterance":
        groups = [np.arange(u.start, u.stop) for u in corpus.utterances]
    else:
        spk = np.array([u.speaker for u in corpus.utterances])
        idx = corpus.utterance_index
        groups = [np.flatnonzero(spk[idx] == s) for s in dict.fromkeys(spk)]
    shifts = []
    for g in groups:
        d = target - centroid[g].mean(axis=0)
        F[g] += d
        shifts.append(float(np.linalg.norm(d)))
    what = "utterance" if method == "utterance" else "speaker"
    unit = corpus.unit_label
    if method == "utterance":
        moved = (f"shifts median {np.median(shifts):.3g} {unit}, max {max(shifts):.3g} {unit} "
                 f"({len(shifts)} utterances)")
    else:  # name each speaker and how far its frames moved
        names = [s or "(unnamed)" for s in dict.fromkeys(spk)]
        moved = "frames moved " + ", ".join(f"{n} by {d:.3g} {unit}" for n, d in zip(names, shifts))
    desc = (f"{what} centring (no reference sensors): each {what}'s mean lip centroid moved to the corpus mean; "
            f"{moved}")
    return replace(corpus, frames=F.reshape(corpus.n_frames, -1).astype(np.float32), registration=desc,
                   history=list(corpus.history) + [f"registration: {desc}"])


def normalise_speakers(corpus: Corpus, *, mode: str = "auto", executor=None) -> Corpus:
    """Per-speaker normalisation before the shape space.

    Parameters
    ----------
    corpus : Corpus
    mode : {"auto", "mean", "mean+scale", "none"}
        ``mean``: subtract each speaker's mean frame and add the pooled mean frame back;
        ``mean+scale``: also scale each speaker's deviations to the pooled RMS spread;
        ``auto``: ``mean`` when utterances name two or more speakers, else nothing.
    executor : engine.scale.executor.DaskExecutor or None
        With a corpus stored in blocks (``engine.recordings.frame_blocks.BlockFrames``), the
        per-speaker sums are computed by one task per block file; None: in-process.

    Returns
    -------
    Corpus
        The input itself when nothing is done, else a new corpus (``history`` says so).
        Frames stored in blocks stay in their files: the new corpus reads them through
        the per-speaker map (:class:`engine.recordings.frame_blocks.SpeakerAffine`), which the
        shape stage's block tasks apply; in-memory frames are normalised into a copy.
    """
    from engine.recordings.frame_blocks import BlockFrames, row_windows

    if mode not in SPEAKER_MODES:
        raise ValueError(f"speaker normalisation {mode!r}; expected one of {', '.join(SPEAKER_MODES)}")
    speakers = corpus.speakers
    if mode == "none" or (mode == "auto" and len(speakers) < 2):
        return corpus
    if mode == "auto":
        mode = "mean"
    affine = speaker_affine(corpus, scale=mode == "mean+scale", executor=executor)
    F = corpus.frames
    if isinstance(F, BlockFrames):
        frames = F.with_normalisation(affine)
    else:
        frames = np.empty(F.shape, dtype=np.float32)
        for a, b in row_windows(*F.shape):
            frames[a:b] = affine.apply(F[a:b], a)
    note = f"speaker normalisation {mode} over {len(speakers)} speakers: {_moved(corpus, speakers, affine)}"
    return replace(corpus, frames=frames, history=list(corpus.history) + [note])


def _moved(corpus, speakers, affine) -> str:
    """What per-speaker normalisation moved, in words: each speaker's shift (RMS over the points, in the
    corpus's unit) and, when scaled, its spread factor."""
    d = np.asarray(affine.mean, np.float64) - np.asarray(affine.grand, np.float64)[None]
    V = max(d.shape[1] // corpus.dims, 1)
    rms = np.sqrt((d ** 2).sum(axis=1) / V)
    unit = corpus.unit_label
    parts = []
    for k, s in enumerate(speakers):
        part = f"{s or '(unnamed)'} by {rms[k]:.3g} {unit}"
        if affine.factor is not None:
            part += f", spread x{float(affine.factor[k]):.3g}"
        parts.append(part)
    return ("each speaker's mean frame moved to the pooled mean frame (RMS over the points): " + "; ".join(parts))


def speaker_affine(corpus: Corpus, *, scale: bool, executor=None):
    """The per-speaker normalisation of :func:`normalise_speakers` as a map of rows.

    Two passes over the frames (window by window in-process, or one task per block file
    on ``executor``): per-speaker sums and counts, then (``scale``) per-speaker sums of
    squared deviations; the partial sums are added on the client in row order.

    Returns
    -------
    engine.recordings.frame_blocks.SpeakerAffine
    """
    from functools import partial

    from engine.recordings.frame_blocks import SpeakerAffine, map_frames

    speakers = corpus.speakers
    code_of = {s: k for k, s in enumerate(speakers)}
    starts = np.asarray(corpus.bounds[:, 0], dtype=np.int64)
    code = np.array([code_of[u.speaker] for u in corpus.utterances], dtype=np.int64)
    S, C = len(speakers), corpus.frames.shape[1]
    sums, counts = np.zeros((S, C)), np.zeros(S, dtype=np.int64)
    for part_sums, part_counts in map_frames(partial(_speaker_sums, utt_starts=starts, utt_code=code, n_speakers=S),
                                             corpus.frames, executor=executor):
        sums += part_sums
        counts += part_counts
    mean = sums / np.maximum(counts, 1)[:, None]
    grand = sums.sum(axis=0) / corpus.n_frames
    factor = None
    if scale:
        ssd = np.zeros(S)
        for part in map_frames(partial(_speaker_squares, utt_starts=starts, utt_code=code, mean=mean),
                               corpus.frames, executor=executor):
            ssd += part
        dev = np.sqrt(ssd / (np.maximum(counts, 1) * C))
        pooled = float(np.sqrt(ssd.sum() / (corpus.n_frames * C)))
        factor = np.where(dev > 0, pooled / np.where(dev > 0, dev, 1.0), 1.0)
    return SpeakerAffine(starts, code, mean, factor, grand)


def _speaker_sums(x, a, b, *, utt_starts, utt_code, n_speakers):
    """Per-speaker float64 column sums (S, C) and row counts (S,) of rows ``[a, b)`` given as ``x``."""
    from engine.recordings.frame_blocks import speaker_runs

    sums, counts = np.zeros((n_speakers, x.shape[1])), np.zeros(n_speakers, dtype=np.int64)
    for s, r0, r1 in speaker_runs(utt_starts, utt_code, a, b):
        sums[s] += x[r0 - a:r1 - a].sum(axis=0, dtype=np.float64)
        counts[s] += r1 - r0
    return sums, counts


def _speaker_squares(x, a, b, *, utt_starts, utt_code, mean, rows=1024):
    """Per-speaker sums (S,) of squared deviations from the speaker's mean frame, rows ``[a, b)``."""
    from engine.recordings.frame_blocks import speaker_runs

    out = np.zeros(len(mean))
    for s, r0, r1 in speaker_runs(utt_starts, utt_code, a, b):
        for c0 in range(r0, r1, rows):
            d = x[c0 - a:min(r1, c0 + rows) - a].astype(np.float64) - mean[s]
            out[s] += float(np.einsum("ij,ij->", d, d))
    return out


def explain_split(states, corpus: Corpus) -> str | None:
    """Why the state graph is split, when its pieces follow speakers or recordings.

    Looks at the weakly connected components of the state graph (or, when it has
    one, its strongly connected components) holding at least 5% of the frames ("pieces").
    Along speakers: each piece's frames are at least 90% one speaker, a different one per
    piece. Along recordings: at least 90% of each piece's frames belong to utterances
    that lie mostly in that piece (pieces are made of whole utterances). Returns a
    sentence naming the pieces, the cause and the fix; else None.
    """
    from scipy.sparse.csgraph import connected_components

    n_weak, weak = connected_components(states.adjacency_, directed=True, connection="weak")
    comp = weak if n_weak > 1 else np.asarray(states.scc_labels_)
    if comp.max() < 1:
        return None
    frame_comp = comp[np.asarray(states.labels_)]
    big = [c for c in np.unique(frame_comp) if np.mean(frame_comp == c) >= 0.05]
    if len(big) < 2:
        return None
    kind = "islands (no transitions between them)" if n_weak > 1 else "strongly connected components"
    utt = corpus.utterance_index
    share = ", ".join(f"{100 * np.mean(frame_comp == c):.0f}%" for c in big)
    spk_of = np.array([u.speaker for u in corpus.utterances])[utt]
    if len(set(spk_of)) >= 2:
        dom = []
        for c in big:
            vals, cnt = np.unique(spk_of[frame_comp == c], return_counts=True)
            dom.append((str(vals[cnt.argmax()]), cnt.max() / cnt.sum()))
        if all(f >= _DOMINANT for _, f in dom) and len({d for d, _ in dom}) == len(dom):
            parts = ", ".join(f"one holds speaker {d} ({100 * f:.0f}% of its frames)" for d, f in dom)
            return (f"the state graph splits into {len(big)} {kind} (holding {share} of the frames) along speakers: "
                    f"{parts}. Cause: speaker differences dominate the shape space. Fix: normalise per speaker "
                    "(build --speaker-norm mean) and register the recordings (import --register)")
    # recordings: every piece is made of whole utterances (those whose frames mostly lie in it)
    home = np.empty(len(corpus.utterances), dtype=comp.dtype)
    for k, u in enumerate(corpus.utterances):
        vals, cnt = np.unique(frame_comp[u.start:u.stop], return_counts=True)
        home[k] = vals[cnt.argmax()]
    own = home[utt] == frame_comp  # frame lies in its utterance's home piece
    if all(own[frame_comp == c].mean() >= _DOMINANT for c in big):
        per = []
        for c in big:
            ids = [u.id for u in corpus.utterances if np.mean(frame_comp[u.start:u.stop] == c) >= 0.5]
            more = " ..." if len(ids) > 3 else ""
            per.append(f"{len(ids)} utterance{'s' * (len(ids) != 1)} ({', '.join(ids[:3])}{more})")
        return (f"the state graph splits into {len(big)} {kind} (holding {share} of the frames) along recordings: "
                f"each utterance lies in one piece: {'; '.join(per)}. Cause: offsets between recordings or "
                "speakers dominate the shape space. Fix: register the recordings (import --register utterance, "
                "or rigid with reference sensors in the layout); name the speakers (import --speaker / "
                "--speaker-from) so that the build normalises per speaker")
    return None


def warn_if_split(states, corpus: Corpus) -> str | None:
    """Warn (:class:`RegistrationSplitWarning`) with :func:`explain_split`'s sentence, if any; returns it."""
    msg = explain_split(states, corpus)
    if msg:
        warnings.warn(msg, RegistrationSplitWarning, stacklevel=3)
    return msg
