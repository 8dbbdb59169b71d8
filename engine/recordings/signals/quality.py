"""Sensor quality: each sensor's fit residual per frame, reported per sensor and utterance, and acted on.

Articulographs compute each sensor's position by fitting a model to the measured
amplitudes; the residual of the fit says how far to trust the position. Carstens AG500
and AG501 ``.pos`` files hold it per channel and frame (the ``rms`` value, the 6th of
7); NDI Wave exports may hold a per-sensor error column. The readers keep it in the
corpus as ``latent["quality_<measure>"]`` (n_frames, n_points), float32, column j for
point j; a value of 0 or less means *not measured* (an unused channel, which the AG501
writes as 0, or a value the reader found out of range and reported).

A sample is **suspect** when its value exceeds the threshold: given by the user
(``lipspace import --quality-threshold``), else :data:`DEFAULT_FACTOR` times the median of
the measured values of every point over the corpus imported (:func:`resolve_threshold`; a
relative rule, since units and typical residuals differ between systems and set-ups).
:func:`quality_rows` reports per point and utterance the median, the share of suspect
samples and the longest run of them. :func:`apply_quality` then does what the user chose
(:class:`QualityPolicy`):

=========  ===========================================================================
``keep``   nothing changes (the report and the corpus history say so);
``mask``   runs of suspect samples up to ``max_gap_s`` long are interpolated linearly
           between the neighbouring good samples (held at an utterance's edge); longer
           runs are left as recorded and named;
``drop``   as ``mask``, and every utterance that still has a longer run is left out,
           named.
=========  ===========================================================================

Nothing is done without a line in the corpus history (``lipspace info`` lists them).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

__all__ = ["QUALITY_PREFIX", "ACTIONS", "DEFAULT_FACTOR", "DEFAULT_MAX_GAP_S", "QualityPolicy", "QualityResult",
           "sensor_quality", "quality_key", "resolve_threshold", "quality_rows", "apply_quality", "action_line",
           "summary_lines", "runs_of", "with_points", "QUALITY_COLUMNS"]

#: latent key prefix of a corpus's sensor quality: ``quality_rms``, ``quality_error``
QUALITY_PREFIX = "quality_"
#: what can be done about suspect samples
ACTIONS = ("keep", "mask", "drop")
#: default threshold: this many times the median measured value over the corpus
DEFAULT_FACTOR = 3.0
#: longest run of suspect samples ``mask`` interpolates, in seconds
DEFAULT_MAX_GAP_S = 0.05
#: columns of the per-point, per-utterance report (:func:`quality_rows`)
QUALITY_COLUMNS = ("utterance", "sensor", "measure", "threshold", "frames", "median", "share_above",
                   "longest_run_frames", "longest_run_s", "runs_above", "interpolated_frames", "action")


@dataclass(frozen=True)
class QualityPolicy:
    """What to do about suspect samples (see the module docstring).

    Parameters
    ----------
    threshold : float or None
        Values above it are suspect; None: :data:`DEFAULT_FACTOR` x the corpus median.
    action : {"keep", "mask", "drop"}
    max_gap_s : float
        Longest run of suspect samples ``mask`` and ``drop`` interpolate.
    """

    threshold: float | None = None
    action: str = "keep"
    max_gap_s: float = DEFAULT_MAX_GAP_S

    def __post_init__(self):
        if self.action not in ACTIONS:
            raise ValueError(f"quality action {self.action!r}; expected one of {', '.join(ACTIONS)}")
        if self.threshold is not None and not (np.isfinite(self.threshold) and self.threshold > 0):
            raise ValueError(f"quality threshold {self.threshold!r}; expected a positive number (in the units of "
                             "the file's quality values, e.g. the AG501's rms)")
        if not (np.isfinite(self.max_gap_s) and 0 <= self.max_gap_s <= 1.0):
            raise ValueError(f"longest gap to interpolate {self.max_gap_s!r} s; expected 0 to 1 s")


def quality_key(measure: str) -> str:
    """The latent key of quality ``measure`` (``"rms"`` -> ``"quality_rms"``)."""
    return QUALITY_PREFIX + measure


def sensor_quality(corpus) -> tuple[str, np.ndarray] | None:
    """``(measure, values (N, P) float64)`` of ``corpus``, NaN where not measured; None when it has none."""
    keys = [k for k in corpus.latent if k.startswith(QUALITY_PREFIX)]
    if not keys:
        return None
    q = np.asarray(corpus.latent[keys[0]], np.float64)
    if q.ndim != 2 or q.shape != (corpus.n_frames, corpus.n_points):
        return None
    return keys[0][len(QUALITY_PREFIX):], np.where(q > 0, q, np.nan)


def with_points(latent: dict, keep, n_points: int) -> dict:
    """``latent`` with the quality arrays cut to the points ``keep`` (when points are dropped, e.g. the reference
    sensors after rigid registration); other signals unchanged."""
    out = dict(latent)
    for k, v in latent.items():
        if k.startswith(QUALITY_PREFIX) and np.ndim(v) == 2 and np.shape(v)[1] == n_points:
            out[k] = np.asarray(v)[:, list(keep)]
    return out


def resolve_threshold(corpora, policy: QualityPolicy) -> tuple[float | None, str]:
    """``(threshold, how it was chosen in words)`` for the corpora imported together; (None, why) without any
    quality values."""
    vals = []
    for c in corpora:
        sq = sensor_quality(c)
        if sq is not None:
            v = sq[1]
            vals.append(v[np.isfinite(v)])
    allv = np.concatenate(vals) if vals else np.zeros(0)
    if allv.size == 0:
        return None, "no quality values"
    if policy.threshold is not None:
        return float(policy.threshold), "given (--quality-threshold)"
    med = float(np.median(allv))
    return DEFAULT_FACTOR * med, (f"{DEFAULT_FACTOR:g} x the median {med:.3g} of every measured sample (default; "
                                  "--quality-threshold sets it)")


def runs_of(mask) -> tuple[np.ndarray, np.ndarray]:
    """Runs of True in a 1-D bool array: ``(starts, lengths)``, int64."""
    m = np.asarray(mask, bool).astype(np.int8)
    d = np.diff(np.r_[0, m, 0])
    starts = np.flatnonzero(d == 1)
    return starts, np.flatnonzero(d == -1) - starts


def quality_rows(corpus, threshold: float, *, interpolated=None, action: str = "keep") -> list[dict]:
    """One row per point and utterance (:data:`QUALITY_COLUMNS`); [] when the corpus has no quality values.

    ``interpolated``: ``{(utterance id, point): frames interpolated}`` from :func:`apply_quality`.
    """
    sq = sensor_quality(corpus)
    if sq is None:
        return []
    measure, Q = sq
    names = corpus.point_names or [f"p{j}" for j in range(corpus.n_points)]
    rows = []
    for u in corpus.utterances:
        seg = Q[u.start:u.stop]
        for j, name in enumerate(names):
            v = seg[:, j]
            ok = np.isfinite(v)
            if not ok.any():
                continue
            above = ok & (v > threshold)
            _, lengths = runs_of(above)
            longest = int(lengths.max()) if lengths.size else 0
            rows.append({"utterance": u.id, "sensor": str(name), "measure": measure, "threshold": float(threshold),
                         "frames": int(ok.sum()), "median": float(np.median(v[ok])),
                         "share_above": float(above.sum() / ok.sum()), "longest_run_frames": longest,
                         "longest_run_s": longest / corpus.rate, "runs_above": int(lengths.size),
                         "interpolated_frames": int((interpolated or {}).get((u.id, j), 0)), "action": action})
    return rows


@dataclass
class QualityResult:
    """What :func:`apply_quality` did to one corpus.

    Attributes
    ----------
    corpus : Corpus or None
        After the action (None when ``drop`` left no utterance).
    rows : list of dict
        :func:`quality_rows` of the corpus as it was read, with what was interpolated.
    interpolated : int
        Samples interpolated (each point counts once per frame).
    long_runs : dict of str to list of str
        Per utterance, its runs longer than the gap allowed (``"UL 0.316 s from 0.104 s"``).
    dropped : list of str
        Utterances left out by ``drop``.
    """

    corpus: object
    rows: list
    interpolated: int = 0
    long_runs: dict = field(default_factory=dict)
    dropped: list = field(default_factory=list)


def apply_quality(corpus, threshold: float, policy: QualityPolicy) -> QualityResult:
    """Do ``policy.action`` about samples above ``threshold`` (module docstring); the corpus's history is not
    changed here (:func:`action_line` says what was done over all the corpora of an import)."""
    sq = sensor_quality(corpus)
    if sq is None:
        return QualityResult(corpus, [])
    _, Q = sq
    if policy.action == "keep":
        return QualityResult(corpus, quality_rows(corpus, threshold, action="keep"))
    max_gap = _max_gap(policy, corpus.rate)
    F = np.array(corpus.frames, dtype=np.float32)
    d, names = corpus.dims, corpus.point_names or [f"p{j}" for j in range(corpus.n_points)]
    long_runs: dict[str, Any]
    done, long_runs = {}, {}
    for u in corpus.utterances:
        for j in range(corpus.n_points):
            v = Q[u.start:u.stop, j]
            starts, lengths = runs_of(np.isfinite(v) & (v > threshold))
            short = lengths <= max_gap
            for s, n in zip(starts[short], lengths[short]):
                _interpolate(F, u.start, u.stop, u.start + int(s), int(n), slice(j * d, (j + 1) * d))
            if short.any():
                done[(u.id, j)] = int(lengths[short].sum())
            if (~short).any():
                k = int(np.argmax(np.where(short, -1, lengths)))
                long_runs.setdefault(u.id, []).append(f"{names[j]} {lengths[k] / corpus.rate:.3f} s from "
                                                      f"{starts[k] / corpus.rate:.3f} s")
    rows = quality_rows(corpus, threshold, interpolated=done, action=policy.action)
    out = replace(corpus, frames=F)
    dropped = []
    if policy.action == "drop" and long_runs:
        dropped = list(long_runs)
        keep = [u.id for u in corpus.utterances if u.id not in long_runs]
        out = out.subset(keep) if keep else None
    return QualityResult(out, rows, sum(done.values()), long_runs, dropped)


def _max_gap(policy, rate) -> int:
    return int(np.floor(policy.max_gap_s * rate + 1e-9))


def action_line(results, threshold: float, policy: QualityPolicy, *, rate: float) -> str:
    """One sentence: what ``policy`` did over ``results`` (:func:`apply_quality` of every corpus imported)."""
    if policy.action == "keep":
        return ("quality: keep: every sample kept as recorded (import with --quality mask to interpolate short "
                "runs above the threshold, or --quality drop to leave out the utterances with longer ones)")
    n_int = sum(r.interpolated for r in results)
    long_runs = {k: v for r in results for k, v in r.long_runs.items()}
    dropped = [u for r in results for u in r.dropped]
    gap = _max_gap(policy, rate)
    text = (f"quality: {policy.action} at threshold {threshold:.3g}: {n_int} samples in runs of at most {gap} "
            f"frames ({policy.max_gap_s * 1000:g} ms) above it interpolated")
    listed = ", ".join(f"{k} ({'; '.join(v)})" for k, v in list(long_runs.items())[:4])
    more = " ..." if len(long_runs) > 4 else ""
    if dropped:
        return text + f"; {len(dropped)} utterance(s) with longer runs dropped: {listed}{more}"
    if long_runs:
        return text + f"; longer runs left as recorded in {len(long_runs)} utterance(s): {listed}{more}"
    return text + "; no longer runs"


def _interpolate(F, lo, hi, start, n, cols):
    """Replace frames ``start .. start + n - 1`` of columns ``cols`` by a line between the neighbouring frames inside
    ``[lo, hi)`` (the one neighbour's value at an utterance's edge)."""
    a, b = start - 1, start + n
    if a < lo and b >= hi:
        return  # the whole utterance: nothing to interpolate from (a longer run than any gap allowed)
    if a < lo:
        F[start:b, cols] = F[b, cols]
    elif b >= hi:
        F[start:hi, cols] = F[a, cols]
    else:
        w = (np.arange(1, n + 1) / (n + 1))[:, None]
        F[start:b, cols] = (1 - w) * F[a, cols] + w * F[b, cols]


def summary_lines(rows, threshold: float, how: str, *, speakers=None) -> list[str]:
    """What the report found, in a few lines: the threshold, then per point with samples above it their share and
    longest run (per speaker when ``speakers``, ``{utterance id: speaker}``, names two or more), the points with
    none in one clause. Printed by import, kept in the history, listed by info."""
    if not rows:
        return []
    measure = rows[0]["measure"]
    speakers = speakers or {}
    per: dict[str, list] = {}
    for r in rows:
        per.setdefault(r["sensor"], []).append(r)
    several = len({speakers.get(r["utterance"], "") for r in rows}) > 1
    clean, lines = [], [f"quality: {measure} above {threshold:.3g} ({how}) is suspect"]
    for name, rs in per.items():
        if not any(r["share_above"] > 0 for r in rs):
            clean.append(f"{name} (median {np.median([r['median'] for r in rs]):.3g})")
            continue
        groups: dict[str, list] = {}
        for r in rs:
            groups.setdefault(speakers.get(r["utterance"], "") if several else "", []).append(r)
        parts = [_group_text(g, grs, several) for g, grs in groups.items()]
        lines.append(f"quality: {name}: " + "; ".join(parts))
    if clean:
        lines.append(f"quality: no {measure} above {threshold:.3g} in {', '.join(clean)}")
    return lines


def _group_text(group, rs, several) -> str:
    frames = sum(r["frames"] for r in rs)
    above = sum(r["share_above"] * r["frames"] for r in rs)
    worst = max(rs, key=lambda r: r["longest_run_frames"])
    med = float(np.median([r["median"] for r in rs]))
    hit = sum(r["share_above"] > 0 for r in rs)
    who = f"speaker {group} " if group else ("no speaker " if several else "")
    run = f", longest run {worst['longest_run_s']:.3f} s in {worst['utterance']}" if worst["longest_run_frames"] else ""
    return (f"{who}median {med:.3g}, {100 * above / max(frames, 1):.1f}% of samples above in {hit} of {len(rs)} "
            f"utterances{run}")
