"""A generated multi-speaker articulograph corpus with the faults of real recordings.

:func:`generate_recordings` makes what a 3-D articulograph export looks like: per
utterance a plain matrix of ``n_sensors x 6`` values (x, y, z, phi, theta, rms) at
250 Hz, sensors UL, LL, LC, RC (lips and corners), TT, TB, TD (tongue), optionally
three head reference sensors (NOSE, LMA, RMA), and no phone labels. It reproduces
the properties that break a naive pipeline:

* each speaker's coordinate origin differs (by ``speaker_offset`` mm) and each has
  its own lip size;
* every utterance sits at another head position (``utterance_offset`` mm s.d.);
* the head moves within an utterance (rotation up to ``head_motion`` degrees),
  moving every sensor; the reference sensors move with the head only;
* the tongue moves more than the lips (its own rhythm), so a shape space over all
  sensors has tongue movement, not lip opening, as its first component.

The true lip aperture (upper-lower lip distance before any of that) is returned
per utterance, so tests and benchmarks can score what "opening" became.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Recording", "generate_recordings", "SENSORS", "REFERENCE_SENSORS", "layout_text"]

SENSORS = ("UL", "LL", "LC", "RC", "TT", "TB", "TD")
REFERENCE_SENSORS = ("NOSE", "LMA", "RMA")
_ROLES = {"UL": "upper_lip", "LL": "lower_lip", "LC": "left_corner", "RC": "right_corner", "TT": "tongue",
          "TB": "tongue", "TD": "tongue", "NOSE": "reference", "LMA": "reference", "RMA": "reference"}


@dataclass
class Recording:
    """One generated utterance: ``matrix`` (n, n_sensors * 6), its speaker and true aperture (n,)."""

    id: str
    speaker: str
    matrix: np.ndarray
    aperture: np.ndarray
    rate: float


def layout_text(reference: bool) -> str:
    """A user layout file for the generated matrices (with or without the reference sensors)."""
    names = SENSORS + (REFERENCE_SENSORS if reference else ())
    lines = ["name: generated-ema", "values: 6", "xyz: 0 1 2"]
    lines += [f"sensor {n} {_ROLES[n]}" for n in names]
    return "\n".join(lines) + "\n"


def _smooth_noise(rng, n, rate, cutoff_hz):
    from scipy.signal import butter, sosfiltfilt

    x = rng.normal(size=n + 200)
    sos = butter(2, cutoff_hz / (rate / 2), output="sos")
    y = sosfiltfilt(sos, x)[100:100 + n]
    return y / (y.std() + 1e-12)


def _rotation(ax, ay, az):
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def generate_recordings(*, n_speakers=3, n_utterances=6, duration_s=(2.0, 3.0), rate=250.0, speaker_offset=100.0,
                        utterance_offset=4.0, head_motion=2.0, reference=False, seed=0) -> list[Recording]:
    """Generate per-utterance articulograph matrices (see the module docstring).

    Parameters
    ----------
    n_speakers, n_utterances : int
        Speakers, and utterances per speaker.
    duration_s : (float, float)
        Range of utterance durations.
    rate : float
        Frame rate (Hz).
    speaker_offset : float
        Distance (mm) between speakers' coordinate origins.
    utterance_offset : float
        S.d. (mm, per axis) of the head position per utterance.
    head_motion : float
        Largest head rotation (degrees) within an utterance (slow drift); 0 = none.
    reference : bool
        Add the head reference sensors NOSE, LMA, RMA (then head motion is removable).
    seed : int

    Returns
    -------
    list of Recording
    """
    rng = np.random.default_rng(seed)
    out = []
    for s in range(n_speakers):
        spk = f"S{s + 1}"
        size = 1.0 + 0.12 * rng.normal()
        origin = np.array([speaker_offset * s, 0.3 * speaker_offset * (s % 2), -0.2 * speaker_offset * s])
        # rest positions (mm; x anterior, y lateral, z vertical) around the mouth
        rest: dict[str, Any] = {"UL": [0, 0, 6], "LL": [0, 0, -6], "LC": [-4, 25, 0], "RC": [-4, -25, 0],
                "TT": [-15, 0, -2], "TB": [-35, 0, 2], "TD": [-55, 0, 0],
                "NOSE": [5, 0, 45], "LMA": [-90, 60, 30], "RMA": [-90, -60, 30]}
        rest = {k: np.array(v, float) * size for k, v in rest.items()}
        for k in range(n_utterances):
            n = int(rate * rng.uniform(*duration_s))
            t = np.arange(n) / rate
            syll = 4.0 + 1.5 * rng.random()
            phase = 2 * np.pi * syll * t + 0.8 * np.cumsum(_smooth_noise(rng, n, rate, 1.0)) / rate
            amp = 0.6 + 0.4 * (0.5 + 0.5 * _smooth_noise(rng, n, rate, 0.7))
            open_ = np.clip(amp * (0.5 - 0.5 * np.cos(phase)), 0, None)  # 0 closed .. ~1 open
            rnd = _smooth_noise(rng, n, rate, 1.5)  # rounding / spreading
            jaw = 0.7 * open_
            P = {name: np.repeat(rest[name][None], n, axis=0) for name in rest}
            P["UL"][:, 2] += 2.5 * size * open_
            P["UL"][:, 0] += 0.5 * size * rnd
            P["LL"][:, 2] -= 9.0 * size * open_
            P["LL"][:, 0] += 0.5 * size * rnd
            for c, sgn in (("LC", 1), ("RC", -1)):
                P[c][:, 1] -= sgn * 1.0 * size * rnd
                P[c][:, 2] -= 2.0 * size * jaw
            tongue = 8.0 * _smooth_noise(rng, n, rate, 5.0)
            for j, name in enumerate(("TT", "TB", "TD")):
                P[name][:, 2] += tongue * (1.2 - 0.3 * j) - 4.0 * jaw
                P[name][:, 0] += 6.0 * _smooth_noise(rng, n, rate, 4.0) * (1 - 0.2 * j)
            aperture = np.linalg.norm(P["UL"] - P["LL"], axis=1)
            names = SENSORS + (REFERENCE_SENSORS if reference else ())
            X = np.stack([P[nm] for nm in names], axis=1)  # (n, S, 3)
            offset = origin + utterance_offset * rng.normal(size=3)
            if head_motion > 0:
                drift = np.stack([_smooth_noise(rng, n, rate, 0.5) for _ in range(3)], axis=1)
                drift *= np.deg2rad(head_motion) / (np.abs(drift).max() + 1e-12)
                shift = 0.5 * np.stack([_smooth_noise(rng, n, rate, 0.5) for _ in range(3)], axis=1)
                X = np.stack([X[i] @ _rotation(*drift[i]).T + shift[i] for i in range(n)])
            X = X + offset
            M = np.zeros((n, len(names), 6))
            M[:, :, :3] = X + 0.05 * rng.normal(size=X.shape)  # sensor noise
            M[:, :, 3:5] = rng.uniform(-90, 90, size=(n, len(names), 2))
            M[:, :, 5] = rng.uniform(0, 5, size=(n, len(names)))
            out.append(Recording(f"{spk}_U{k + 1:02d}", spk, M.reshape(n, -1), aperture, float(rate)))
    return out
