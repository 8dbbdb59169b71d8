"""Generated corpora made the way real recordings are: written in the recording systems' formats, read back
through the importers, registered and resampled as ``lipspace import`` does.

Tests, the figure gallery and benchmarks need corpora of every kind a user brings, not only the
synthetic talker's lip mesh:

* :func:`articulograph_corpus`: 3-D articulograph matrices (:mod:`engine.talker.multispeaker`:
  UL, LL, LC, RC of several speakers at 250 Hz, head motion, per-speaker origins), read with
  the ``ema7x6`` layout keeping the four lip sensors, no phone labels;
* :func:`midsagittal_corpus`: MOCHA-TIMIT-style EST Track files (binary, 500 Hz, 1/100 mm, the
  20 MOCHA channels, x growing backwards) with a ``.lab`` alignment beside each whose final pause
  runs past the data, as MOCHA's do; 2-D, upper lip, lower lip and lower incisor;
* :func:`video_corpus`: short MP4 videos whose FaceMesh landmarks move as a talking mouth
  (a face tracked once in scikit-image's astronaut photo, its lips opened and closed by the
  generated aperture, its head swaying), read by :func:`engine.io.video.clips.read_video` with
  those landmarks; 80 lip points with FaceMesh's lip surface. Needs the ``[video]`` extra.

Each returns a :class:`engine.recordings.corpus.Corpus` at the analysis rate (60 Hz).
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

__all__ = ["articulograph_corpus", "midsagittal_corpus", "video_corpus", "ANALYSIS_RATE"]

#: the rate every example is resampled to, as import does by default
ANALYSIS_RATE = 60.0


def articulograph_corpus(*, n_speakers=2, n_utterances=2, duration_s=(2.0, 2.0), seed=11, axes=None,
                         name="ema"):
    """Generated 4-sensor articulograph recordings (ema7x6: UL, LL, LC, RC kept; no phone labels) as import
    makes them (utterance centring, 60 Hz), each utterance naming its speaker. ``axes`` (3, 3): the lab's
    coordinates are ``axes @`` the generator's (x anterior, y left, z up)."""
    from engine.io import concat, resample
    from engine.io.readers.matrix import corpus_from_matrix
    from engine.recordings.corpus import Utterance
    from engine.recordings.layouts import BUILTIN
    from engine.recordings.registration import register
    from engine.talker.multispeaker import generate_recordings

    parts = []
    for r in generate_recordings(n_speakers=n_speakers, n_utterances=n_utterances, duration_s=duration_s,
                                 seed=seed):
        M = r.matrix
        if axes is not None:
            M = M.reshape(M.shape[0], -1, 6).copy()
            M[:, :, :3] = M[:, :, :3] @ np.asarray(axes, float).T
            M = M.reshape(M.shape[0], -1)
        c = corpus_from_matrix(f"{r.id}.mat", M, BUILTIN["ema7x6"], rate=r.rate)
        parts.append(replace(c, utterances=[Utterance(r.id, 0, c.n_frames, speaker=r.speaker)], name=r.id))
    return resample(register(concat(parts, name=name), method="utterance"), ANALYSIS_RATE)


def _phones_from_aperture(open_, rate, *, closed=0.25):
    """A plausible alignment of an opening signal: closures as /b/ or /m/, openings as vowels, a pause at
    each end; ``(start, end, label)`` in seconds."""
    n = len(open_)
    shut = open_ < closed
    edges = np.flatnonzero(np.diff(shut.astype(np.int8))) + 1
    bounds = np.r_[0, edges, n]
    out = []
    vowels, stops = ("a", "i", "o", "e"), ("b", "m", "p")
    for k, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])):
        t0, t1 = a / rate, b / rate
        if k == 0 or k == len(bounds) - 2:
            out.append((t0, t1, "sil"))
        else:
            out.append((t0, t1, stops[k % 3] if shut[a] else vowels[k % 4]))
    return out


def midsagittal_corpus(folder, *, n_utterances=4, duration_s=(2.0, 2.5), seed=3, name="mocha-style"):
    """MOCHA-TIMIT-style 2-D recordings written to ``folder`` and imported (see the module docstring).

    Each utterance is an EST Track binary ``.ema`` (500 Hz, the 20 MOCHA channels in 1/100 mm) and a
    ``.lab`` whose final pause runs 0.25 s past the data; read with :func:`engine.io.read_corpus`
    (upper lip, lower lip, lower incisor), joined, centred per utterance and resampled to 60 Hz.
    """
    from engine.io import concat, read_corpus, resample
    from engine.io.readers.ema import MOCHA_CHANNELS
    from engine.io.writers.est_track import write_est_track
    from engine.recordings.registration import register
    from engine.talker.multispeaker import generate_recordings

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rate = 500.0
    parts = []
    recs = generate_recordings(n_speakers=1, n_utterances=n_utterances, duration_s=duration_s, rate=rate,
                               head_motion=0.5, seed=seed)
    for k, r in enumerate(recs):
        P = r.matrix.reshape(r.matrix.shape[0], -1, 6)[:, :, :3]  # UL, LL, LC, RC, TT, TB, TD; x fwd, y left, z up
        n = len(P)
        ul, ll, tt = P[:, 0], P[:, 1], P[:, 4]
        ap = np.linalg.norm(ul - ll, axis=1)
        open_ = (ap - ap.min()) / max(float(np.ptp(ap)), 1e-9)
        # the lower incisor rides the jaw: 12 mm behind and 9 mm below the lower lip, with most of its drop
        li = ll + np.array([-12.0, 0.0, -9.0]) + np.outer(0.35 * (ll[:, 2] - ll[:, 2].mean()), [0, 0, 1])
        ui = ul + np.array([-11.0, 0.0, -10.0])
        sensors = {"UI": ui, "LI": li, "UL": ul, "LL": ll, "TT": tt, "TB": P[:, 5], "TD": P[:, 6],
                   "V": P[:, 6] + [-25.0, 0, 8], "S15": P[:, 6] * 0, "BN": ui * 0 + [10.0, 0, 40]}
        vals = np.zeros((n, len(MOCHA_CHANNELS)), np.float64)
        for j, ch in enumerate(MOCHA_CHANNELS):
            s, axis = ch.rsplit("_", 1)
            xyz = sensors[s]
            # MOCHA's x grows towards the back of the head, y upwards; values in 1/100 mm
            vals[:, j] = 100.0 * (-xyz[:, 0] if axis == "x" else xyz[:, 2])
        uid = f"msak0_{k + 1:03d}"
        write_est_track(folder / f"{uid}.ema", np.arange(n) / rate, vals, [c.lower() for c in MOCHA_CHANNELS])
        phones = _phones_from_aperture(open_, rate)
        s0, _, lab = phones[-1]
        phones[-1] = (s0, n / rate + 0.25, lab)  # the final pause runs past the data, as MOCHA's .lab do
        (folder / f"{uid}.lab").write_text("".join(f"{a:.4f} {b:.4f} {lab}\n" for a, b, lab in phones))
        c = read_corpus(folder / f"{uid}.ema", alignment=folder / f"{uid}.lab")
        parts.append(replace(c, utterances=[replace(c.utterances[0], id=uid, speaker="msak0")], name=uid))
    return resample(register(concat(parts, name=name), method="utterance"), ANALYSIS_RATE)


def _talking_landmarks(base, open_, rate, rng):
    """FaceMesh landmarks (n, 97, 3) of ``base`` (97, 3) with the mouth opened by ``open_`` (n,) in 0..1, the
    lips rounded and spread by a slow signal of their own, the head swaying (a similarity per frame in the image
    plane) and the tracker's jitter (0.3 px)."""
    from engine.io.video.facemesh import LIP_POINTS
    from engine.talker.multispeaker import _smooth_noise

    n_lip = len(LIP_POINTS)
    lips = base[:n_lip]
    # each ring of 20: its lower half from the right corner (0) to the left one (10), then its upper half
    pos = np.arange(n_lip) % 20
    lower, upper = (pos > 0) & (pos < 10), pos > 10
    mid_y = float(lips[pos % 10 == 0, 1].mean())
    width = float(np.ptp(lips[:, 0]))
    depth = np.abs(lips[:, 1] - mid_y) / max(float(np.abs(lips[:, 1] - mid_y).max()), 1e-9)
    # the lower lip drops, the upper rises, each as a whole (the tracker gives y up)
    weight = (np.where(lower, -0.2, 0.0) + np.where(upper, 0.05, 0.0)) * width
    frames = np.repeat(base[None], len(open_), axis=0).astype(np.float64)
    frames[:, :n_lip, 1] += open_[:, None] * weight[None]
    frames[:, :n_lip, 0] -= 0.06 * width * open_[:, None] * (lips[:, 0] - lips[:, 0].mean())[None] / width
    spread = 0.08 * _smooth_noise(rng, len(open_), rate, 1.2)  # rounding (< 0) and spreading (> 0)
    frames[:, :n_lip, 0] += spread[:, None] * (lips[:, 0] - lips[:, 0].mean())[None]
    frames[:, :n_lip, 2] -= 0.3 * width * spread[:, None] * (1.0 - depth)[None] * 0.2
    frames += 0.3 * rng.normal(size=frames.shape)
    t = np.arange(len(open_)) / rate
    ang = np.deg2rad(3.0) * np.sin(2 * np.pi * t / 2.3 + rng.uniform(0, 6))
    scale = 1.0 + 0.03 * np.sin(2 * np.pi * t / 3.1)
    centre = base[:, :2].mean(axis=0)
    c, s = np.cos(ang), np.sin(ang)
    xy = frames[:, :, :2] - centre
    frames[:, :, 0] = centre[0] + scale[:, None] * (c[:, None] * xy[..., 0] - s[:, None] * xy[..., 1])
    frames[:, :, 1] = centre[1] + scale[:, None] * (s[:, None] * xy[..., 0] + c[:, None] * xy[..., 1])
    frames[:, :, 2] *= scale[:, None]
    return frames.astype(np.float32)


def video_corpus(folder, *, n_clips=3, duration_s=2.4, rate=25.0, seed=7, name="video"):
    """Talking-face MP4 clips written to ``folder`` and imported (see the module docstring).

    The astronaut photo's face is tracked once (MediaPipe FaceMesh); each clip's landmarks are that
    face with its mouth moved by a generated aperture (:mod:`engine.talker.multispeaker`'s) and its head
    swaying; the clips themselves are small MP4 files at ``rate`` frames per second, read by
    :func:`engine.io.video.clips.read_videos`'s path with the landmarks given (one pooled head template).
    """
    from skimage import data as skdata

    from engine.io import concat, resample
    from engine.io.video.clips import head_pose_model, read_video
    from engine.io.video.facemesh import LIP_POINTS, FaceTracker
    from engine.io.video.synth import write_video
    from engine.talker.multispeaker import generate_recordings

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    face = np.ascontiguousarray(skdata.astronaut()[0:256, 96:352])
    with FaceTracker() as tracker:
        base = tracker.track(face)
    if base is None:
        raise RuntimeError("FaceMesh found no face in the astronaut photo")
    rng = np.random.default_rng(seed)
    recs = generate_recordings(n_speakers=1, n_utterances=n_clips, duration_s=(duration_s, duration_s), rate=rate,
                               seed=seed)
    tracks, paths = [], []
    for k, r in enumerate(recs):
        ap = r.aperture
        open_ = (ap - ap.min()) / max(float(np.ptp(ap)), 1e-9)
        lm = _talking_landmarks(np.asarray(base, np.float64), open_, rate, rng)
        path = folder / f"talk{k + 1}.mp4"
        still = np.full((32, 32, 3), 128, np.uint8)
        write_video(path, (still for _ in range(len(lm))), rate)
        tracks.append((lm, np.ones(len(lm), bool)))
        paths.append(path)
    n_lip = len(LIP_POINTS)
    pose = head_pose_model().fit(np.concatenate([lm[:, n_lip:] for lm, _ in tracks]))
    parts = [read_video(p, landmarks=t, pose=pose, alignment=False) for p, t in zip(paths, tracks)]
    return resample(concat(parts, name=name), ANALYSIS_RATE)
