"""A lab's articulograph recordings, generated as the devices and labs write them.

For tests, benchmarks and the user guide's walk-through: the movements come from
:func:`engine.talker.multispeaker.generate_recordings` (speakers with their own origins
and lip sizes, head motion, tongue moving more than the lips); this module writes them
the way a lab's folder holds them:

* **Carstens AG501** ``.pos`` sweeps: the ``AG50xDATA_V003`` text header (its length in
  bytes on line 2, ``NumberOfChannels``, ``SamplingFrequencyHz``, the calcpos / normpos
  lines, a NUL), then float32 frames of 16 channels x 7 values (x, y, z, phi, theta,
  rms, extra); sockets 1-10 hold the lab's sensors (:data:`SOCKETS`), 11-16 are unused
  (all zero, as the device writes them);
* **Carstens AG500** ``.pos``: no header, 12 channels x 7 values at 200 Hz;
* **NDI Wave** TSV exports: ``Wav Time``, then per sensor ``Sensor N Id``, ``Frame``,
  ``State`` (``OK`` or ``Missing``), ``Q0 Qx Qy Qz Tx Ty Tz`` and an ``Error`` column;
* file names ``<speaker><sex><emotion><text>.pos`` (``XYZFNE01.pos``) and the
  metadata table labs keep beside them (``;``-separated, a byte-order mark, as a
  spreadsheet saves it).

A sensor can be made bad for one speaker (:class:`BadSensor`): its rms raised and
bursts of high rms in which its position jumps, as a loose or damaged coil does.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["SOCKETS", "ROLES", "Sweep", "BadSensor", "lab_sweeps", "pos_bytes", "write_pos", "layout_text",
           "wave_tsv", "metadata_csv", "write_ag501_folder"]

#: the lab's sensors in AG501 socket order (channels 1..10); channels 11..16 unused
SOCKETS = ("NOSE", "LMA", "RMA", "TT", "TB", "UL", "LL", "LC", "RC", "TD")
ROLES = {"NOSE": "reference", "LMA": "reference", "RMA": "reference", "TT": "tongue", "TB": "tongue",
         "UL": "upper_lip", "LL": "lower_lip", "LC": "left_corner", "RC": "right_corner", "TD": "tongue"}
#: each sensor's typical rms (a healthy coil), AG501 units
_BASE_RMS = {"NOSE": 1.4, "LMA": 2.2, "RMA": 2.0, "TT": 3.8, "TB": 4.4, "UL": 2.6, "LL": 3.1, "LC": 0.9,
             "RC": 1.2, "TD": 3.5}
_HEADER_LINES = ("sweepsaver.version=v2.3-r3359", "recorded=2016-11-21T17:54:58.502", "calcpos.version=v2.3-r3359",
                 "calcpos.timestamp=2016-11-22T12:52:28.284", "calcpos.ampfilter=FIR_kaiserd_P_95_105_60_1250",
                 "normpos.version=v2.3-r3359", "normpos.timestamp=2016-11-22T13:19:56.664")


@dataclass
class Sweep:
    """One recording: its name parts, positions (n, 10, 3) in socket order (mm) and rms (n, 10)."""

    speaker: str
    sex: str
    emotion: str
    text: str
    positions: np.ndarray
    rms: np.ndarray
    rate: float

    @property
    def name(self) -> str:
        return f"{self.speaker}{self.sex}{self.emotion}{self.text}"


@dataclass(frozen=True)
class BadSensor:
    """A coil that fails for one speaker: ``median`` rms throughout, and in ``share`` of the frames bursts of
    ``burst`` rms in which its position jumps by up to ``jump_mm``."""

    speaker: str
    sensor: str = "UL"
    median: float = 8.6
    share: float = 0.18
    burst: float = 14.0
    jump_mm: float = 3.0


def _smooth(rng, n, rate, hz):
    from scipy.signal import butter, sosfiltfilt

    x = rng.normal(size=n + 200)
    y = sosfiltfilt(butter(2, hz / (rate / 2), output="sos"), x)[100:100 + n]
    return y / (y.std() + 1e-12)


def lab_sweeps(speakers=(("XYZ", "F"), ("ABC", "M")), emotions=("NE", "AN"), texts: int = 2, *, rate: float = 250.0,
               duration_s=(1.0, 1.3), emotion_opening=None, bad: BadSensor | None = None, seed: int = 0):
    """Recordings of every speaker x emotion x text (module docstring).

    Parameters
    ----------
    speakers : sequence of (code, sex)
    emotions : sequence of str
        Two-letter emotion codes.
    texts : int
        Texts per speaker and emotion (numbered 01, 02 ...).
    emotion_opening : dict of str to float, optional
        Factor on the lips' movement per emotion (e.g. ``{"AN": 1.3}``: angry opens wider).
    bad : BadSensor, optional
    seed : int

    Returns
    -------
    list of Sweep
    """
    from engine.talker.multispeaker import generate_recordings

    per = len(emotions) * texts
    recs = generate_recordings(n_speakers=len(speakers), n_utterances=per, duration_s=duration_s, rate=rate,
                               reference=True, seed=seed)
    rng = np.random.default_rng(seed + 1)
    order = ("UL", "LL", "LC", "RC", "TT", "TB", "TD", "NOSE", "LMA", "RMA")  # the generator's sensor order
    out = []
    for k, r in enumerate(recs):
        (spk, sex), j = speakers[k // per], k % per
        emo, txt = emotions[j // texts], f"{j % texts + 1:02d}"
        n = r.matrix.shape[0]
        X = r.matrix.reshape(n, len(order), 6)[:, :, :3]
        P = np.stack([X[:, order.index(s)] for s in SOCKETS], axis=1)
        f = (emotion_opening or {}).get(emo, 1.0)
        if f != 1.0:
            for s in ("UL", "LL"):
                i = SOCKETS.index(s)
                P[:, i] = P[:, i].mean(axis=0) + f * (P[:, i] - P[:, i].mean(axis=0))
        R = np.stack([_BASE_RMS[s] * np.exp(0.08 * _smooth(rng, n, rate, 2.0)) for s in SOCKETS], axis=1)
        if bad is not None and bad.speaker == spk:
            i = SOCKETS.index(bad.sensor)
            R[:, i] *= bad.median / _BASE_RMS[bad.sensor]
            wobble = _smooth(rng, n, rate, 3.0)
            burst = wobble > np.quantile(wobble, 1 - bad.share)
            R[burst, i] = bad.burst * (1 + 0.1 * rng.random(int(burst.sum())))
            P[burst, i] += bad.jump_mm * rng.normal(size=(int(burst.sum()), 3)) / np.sqrt(3)
        out.append(Sweep(spk, sex, emo, txt, P, R, float(rate)))
    return out


def pos_bytes(positions, rms, *, rate: float = 250.0, channels: int = 16, header: bool = True, seed: int = 0):
    """An AG501 (``header``) or AG500 ``.pos`` file's bytes: ``positions`` (n, k, 3) and ``rms`` (n, k) in the
    first k of ``channels`` channels, angles and extra filled as the device fills them, unused channels 0."""
    P = np.asarray(positions, np.float64)
    n, k, _ = P.shape
    rng = np.random.default_rng(seed)
    M = np.zeros((n, channels, 7), np.float32)
    M[:, :k, :3] = P
    M[:, :k, 3] = rng.uniform(-180, 180, size=k) + np.cumsum(rng.normal(0, 0.05, (n, k)), axis=0)
    M[:, :k, 4] = rng.uniform(-60, 60, size=k) + np.cumsum(rng.normal(0, 0.05, (n, k)), axis=0)
    M[:, :k, 5] = rms
    body = M.astype("<f4").tobytes()
    if not header:
        return body
    active = ",".join(str(i + 1) for i in range(k))
    text = "\n".join((f"NumberOfChannels={channels}", f"SamplingFrequencyHz={rate:g}", *_HEADER_LINES,
                      f"normpos.FIR_kaiserd_P_40_50_60_{rate:g}={active}")) + "\n"
    magic = b"AG50xDATA_V003\n"
    size = len(magic) + 9 + len(text.encode("latin-1")) + 1
    return magic + f"{size:08d}\n".encode() + text.encode("latin-1") + b"\x00" + body


def write_pos(path, sweep_or_positions, rms=None, **kw) -> Path:
    """Write a ``.pos`` file from a :class:`Sweep` (or positions and rms); returns the path."""
    if isinstance(sweep_or_positions, Sweep):
        s = sweep_or_positions
        data = pos_bytes(s.positions, s.rms, rate=s.rate, **kw)
    else:
        data = pos_bytes(sweep_or_positions, rms, **kw)
    path = Path(path)
    path.write_bytes(data)
    return path


def layout_text(name: str = "lab-ag501", base: str = "ag501") -> str:
    """The lab's layout file: its sensors in socket order with their roles (unused sockets as ``ch11`` ...)."""
    lines = [f"name: {name}", f"base: {base}"]
    lines += [f"sensor {s} {ROLES[s]}" for s in SOCKETS]
    n = 16 if base == "ag501" else 12
    lines += [f"sensor ch{i + 1}" for i in range(len(SOCKETS), n)]
    return "\n".join(lines) + "\n"


def wave_tsv(positions, *, rate: float = 100.0, state=None, error=None, seed: int = 0) -> str:
    """An NDI Wave TSV export of ``positions`` (n, k, 3): ``state`` (n, k) of str (default ``OK``), ``error``
    (n, k) of the sensors' fit error (default none written)."""
    P = np.asarray(positions, np.float64)
    n, k, _ = P.shape
    rng = np.random.default_rng(seed)
    head = ["Wav Time"]
    for j in range(k):
        head += [f"Sensor {j + 1} Id", "Frame", "State", "Q0", "Qx", "Qy", "Qz", "Tx", "Ty", "Tz"]
        if error is not None:
            head.append("Error")
    lines = ["\t".join(head)]
    q = rng.normal(size=(k, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    for i in range(n):
        row = [f"{i / rate:.4f}"]
        for j in range(k):
            st = "OK" if state is None else str(state[i][j])
            xyz = ["nan"] * 3 if st != "OK" else [f"{v:.3f}" for v in P[i, j]]
            row += [str(j + 1), str(1000 + i), st, *(f"{v:.4f}" for v in q[j]), *xyz]
            if error is not None:
                row.append(f"{error[i][j]:.3f}")
        lines.append("\t".join(row))
    return "\n".join(lines) + "\n"


def metadata_csv(sweeps, *, sep: str = ";", bom: bool = True, leave_out=(), extra=()) -> str:
    """The lab's metadata table: ``File;Speaker;Sex;Emotion;Text;Session`` one row per sweep (not those whose
    names are in ``leave_out``), plus ``extra`` rows (names of files that do not exist)."""
    rows = [sep.join(("File", "Speaker", "Sex", "Emotion", "Text", "Session"))]
    for s in sweeps:
        if s.name not in leave_out:
            rows.append(sep.join((f"{s.name}.pos", s.speaker, s.sex, s.emotion, s.text, "1")))
    for name in extra:
        rows.append(sep.join((f"{name}.pos", name[:3], name[3], name[4:6], name[6:], "2")))
    return ("\ufeff" if bom else "") + "\r\n".join(rows) + "\r\n"


def write_ag501_folder(folder, sweeps, *, layout: bool = True, metadata: bool = True, **meta_kw) -> list[Path]:
    """Write every sweep as ``<name>.pos`` into ``folder`` (created), the lab's layout (``lab.layout``) and
    metadata table (``metadata.csv``) beside them, and a notes file a lab's folder has; returns the .pos
    paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = [write_pos(folder / f"{s.name}.pos", s, seed=i) for i, s in enumerate(sweeps)]
    if layout:
        (folder / "lab.layout").write_text(layout_text(), encoding="utf-8")
    if metadata:
        (folder / "metadata.csv").write_text(metadata_csv(sweeps, **meta_kw), encoding="utf-8", newline="")
    (folder / "notes.txt").write_text("session notes: coil UL re-glued after the break\n", encoding="utf-8")
    return paths
