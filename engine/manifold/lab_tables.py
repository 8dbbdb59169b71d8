"""What an articulograph lab reads off a manifold's tables: metadata fields, derived tracks, gestures.

* :func:`with_field_columns` puts one column per metadata field of the utterances
  (:mod:`engine.recordings.metadata`) after ``speaker`` in a per-frame
  :class:`engine.manifold.frame_table.FrameTable`;
* :func:`with_track_columns` appends derived tracks (:mod:`engine.recordings.signals.tracks`),
  each with its unit and the filter applied;
* :func:`gesture_table` gives one row per gesture (:mod:`engine.recordings.signals.gestures`):
  utterance, fields, track, the landmark times, durations, peak velocities and the state
  of the manifold's state graph at each landmark;
* :func:`gesture_tier` is a gesture set's Praat point tier for one utterance, and
  :func:`write_textgrids_with_gestures` writes the per-utterance TextGrids with those tiers
  after the usual ones (:func:`engine.manifold.frame_table.utterance_tiers`).

Tracks and gestures are computed on the manifold's corpus as built (``Manifold.corpus_``:
registered, resampled and normalised per speaker as the build did).
"""
from __future__ import annotations

import numpy as np

from engine.manifold.frame_table import FrameTable

__all__ = ["with_field_columns", "with_track_columns", "gesture_table", "gesture_tier", "tier_name",
           "write_textgrids_with_gestures", "LANDMARK_COLUMNS"]

#: per-gesture table column of each landmark time
LANDMARK_COLUMNS = ("gons_s", "pvel_s", "nons_s", "maxc_s", "noffs_s", "pvel2_s", "goffs_s")
_LANDMARK_WORDS = ("gesture onset", "peak velocity toward the target", "nucleus onset", "maximum constriction",
                   "nucleus offset", "peak velocity away from the target", "gesture offset")


def _insert_after(table: FrameTable, after: str, cols: dict, units: dict, desc: dict) -> FrameTable:
    names = list(table.columns)
    at = names.index(after) + 1 if after in names else len(names)
    order = names[:at] + list(cols) + names[at:]
    merged = {**table.columns, **cols}
    return FrameTable(columns={k: merged[k] for k in order}, units={**table.units, **units},
                      descriptions={**table.descriptions, **desc}, notes=list(table.notes), rate=table.rate,
                      source=table.source)


def with_field_columns(table: FrameTable, corpus) -> FrameTable:
    """``table`` (one row per frame of ``corpus``) with a column per metadata field other than speaker, after
    ``speaker``; text, missing (None) where an utterance lacks the field."""
    from engine.recordings.metadata import field_names, field_values

    names = [n for n in field_names(corpus) if n != "speaker"]
    clash = [n for n in names if n in table.columns]
    if clash:
        raise ValueError(f"metadata field(s) {clash} would replace columns of the table; rename them on import")
    lengths = np.diff(corpus.bounds, axis=1)[:, 0]
    cols, units, desc = {}, {}, {}
    for n in names:
        vals = np.array([v or None for v in field_values(corpus, n).tolist()], dtype=object)
        cols[n] = np.repeat(vals, lengths)
        units[n] = ""
        desc[n] = f"metadata field '{n}' of the frame's utterance (missing where the utterance has none)"
    return _insert_after(table, "speaker", cols, units, desc)


def with_track_columns(table: FrameTable, tracks) -> FrameTable:
    """``table`` with a column per :class:`engine.recordings.signals.tracks.Track` (named by
    :func:`engine.recordings.signals.tracks.column_name`), appended; ValueError when a name is taken."""
    from engine.recordings.signals.tracks import column_name

    cols, units, desc = {}, {}, {}
    for tr in tracks:
        name = column_name(tr.name)
        if name in table.columns or name in cols:
            raise ValueError(f"track {tr.name!r} would be column {name!r}, which the table already has")
        cols[name] = np.asarray(tr.values, np.float64)
        units[name] = tr.unit
        desc[name] = tr.description
    out = _insert_after(table, "", cols, units, desc)
    filters = sorted({t.lowpass_hz for t in tracks if t.lowpass_hz})
    if filters:
        out.notes.append(f"derived tracks: positions low-passed at {', '.join(f'{f:g}' for f in filters)} Hz "
                         "(Butterworth, forward and backward: zero phase) before they were derived")
    return out


def gesture_table(manifold, gesture_sets, *, source: str = "") -> FrameTable:
    """One row per gesture of every set in ``gesture_sets`` (module docstring).

    Returns
    -------
    FrameTable
        Columns ``utterance, speaker, <fields>, track, gesture, target, gons_s .. goffs_s, gesture_s,
        toward_s, nucleus_s, away_s, pvel_toward, pvel_away, maxc_value, state_gons .. state_goffs``.
    """
    from engine.recordings.metadata import field_names, field_values
    from engine.recordings.signals.gestures import LANDMARKS

    c = manifold.corpus_
    fields = [n for n in field_names(c) if n != "speaker"]
    per_field = {n: field_values(c, n) for n in fields}
    labels = np.asarray(manifold.states_.labels_, np.int64)
    rows: dict[str, list] = {k: [] for k in ("utterance", "speaker", *fields, "track", "gesture", "target",
                                             *LANDMARK_COLUMNS, "gesture_s", "toward_s", "nucleus_s", "away_s",
                                             "pvel_toward", "pvel_away", "maxc_value",
                                             *(f"state_{x.lower()}" for x in LANDMARKS))}
    units = {}
    for gs in gesture_sets:
        frames = gs.frames(c.bounds)
        count: dict[int, int] = {}
        for g in range(len(gs)):
            k = int(gs.utterance[g])
            u = c.utterances[k]
            count[k] = count.get(k, 0) + 1
            t = gs.times[g]
            rows["utterance"].append(u.id)
            rows["speaker"].append(u.speaker or None)
            for n in fields:
                rows[n].append(per_field[n][k] or None)
            rows["track"].append(gs.track)
            rows["gesture"].append(count[k])
            rows["target"].append(gs.target)
            for col, x in zip(LANDMARK_COLUMNS, t):
                rows[col].append(x)
            rows["gesture_s"].append(t[6] - t[0])
            rows["toward_s"].append(t[2] - t[0])
            rows["nucleus_s"].append(t[4] - t[2])
            rows["away_s"].append(t[6] - t[4])
            rows["pvel_toward"].append(gs.peak_velocity[g, 0])
            rows["pvel_away"].append(gs.peak_velocity[g, 1])
            rows["maxc_value"].append(gs.maxc_value[g])
            for x, f in zip(LANDMARKS, frames[g]):
                rows[f"state_{x.lower()}"].append(float(labels[f]) if f >= 0 else np.nan)
        units[gs.track] = gs.unit
    cols = {}
    for col, v in rows.items():
        if col in ("utterance", "speaker", "track", "target", *fields):
            cols[col] = np.array(v, dtype=object)
        elif col == "gesture":
            cols[col] = np.array(v, dtype=np.int64)
        else:
            cols[col] = np.array(v, dtype=np.float64)
    unit = "; ".join(f"{k}: {u}" for k, u in units.items() if u) or "the track's unit"
    meta_units = {**{c_: "s" for c_ in LANDMARK_COLUMNS}, "gesture_s": "s", "toward_s": "s", "nucleus_s": "s",
                  "away_s": "s", "pvel_toward": f"per s ({unit})", "pvel_away": f"per s ({unit})",
                  "maxc_value": unit, "gesture": "index", **{f"state_{x.lower()}": "index" for x in LANDMARKS}}
    desc = {"utterance": "utterance id", "speaker": "speaker (missing when the corpus does not say)",
            "track": "the track the gesture was found on", "gesture": "the gesture's number within its utterance",
            "target": "min: a movement to a minimum of the track (a constriction), max: to a maximum",
            "gesture_s": "gesture duration (goffs - gons)", "toward_s": "movement toward the target (nons - gons)",
            "nucleus_s": "nucleus duration (noffs - nons)", "away_s": "movement away from the target (goffs - noffs)",
            "pvel_toward": "peak speed of the movement toward the target",
            "pvel_away": "peak speed of the movement away from the target",
            "maxc_value": "the track at the maximum constriction"}
    desc.update({n: f"metadata field '{n}'" for n in fields})
    for col, word in zip(LANDMARK_COLUMNS, _LANDMARK_WORDS):
        desc[col] = f"time of the {word}, from the start of the utterance (missing where not found)"
    for x, word in zip(LANDMARKS, _LANDMARK_WORDS):
        desc[f"state_{x.lower()}"] = f"state of the manifold's state graph at the {word}'s frame"
    thr = sorted({gs.threshold for gs in gesture_sets})
    lp = sorted({gs.lowpass_hz for gs in gesture_sets if gs.lowpass_hz})
    notes = [f"landmarks at {', '.join(f'{100 * x:g}' for x in thr)} % of each peak speed"
             + (f"; tracks low-passed at {', '.join(f'{x:g}' for x in lp)} Hz (zero phase)" if lp else "")]
    return FrameTable(columns=cols, units={k: meta_units.get(k, "") for k in cols}, descriptions=desc, notes=notes,
                      rate=float(c.rate), source=source)


def tier_name(gs) -> str:
    """The TextGrid tier of a gesture set: ``gestures`` (lip aperture), else ``gestures_<track>``."""
    return "gestures" if gs.track == "lip_aperture" else f"gestures_{gs.track}"


def gesture_tier(gs, uid):
    """The point tier of the gestures of utterance ``uid``: one point per landmark found, labelled with its name
    (landmarks at the same time share a point, ``NONS+MAXC``)."""
    from engine.io.writers.praat import PointTier
    from engine.recordings.signals.gestures import LANDMARKS

    pts = []
    for g in gs.of_utterance(uid):
        for name, t in zip(LANDMARKS, gs.times[g]):
            if np.isfinite(t):
                pts.append((float(t), name))
    pts.sort(key=lambda p: p[0])
    merged = []  # Praat keeps one point per time: landmarks at one time share it ("NONS+MAXC")
    for t, lab in pts:
        if merged and abs(merged[-1][0] - t) < 1e-9:
            merged[-1] = (merged[-1][0], f"{merged[-1][1]}+{lab}")
        else:
            merged.append((t, lab))
    return PointTier(tier_name(gs), merged)


def write_textgrids_with_gestures(manifold, table, directory, gesture_sets, *, names=None) -> list:
    """One TextGrid per utterance into ``directory``: the tiers of
    :func:`engine.manifold.frame_table.utterance_tiers`, then a gesture tier per set; each written atomically."""
    from pathlib import Path

    from engine.io.writers.praat import textgrid_names, write_textgrid
    from engine.manifold.frame_table import utterance_tiers

    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    utts = manifold.corpus_.utterances
    names = list(names) if names is not None else textgrid_names(u.id for u in utts)
    out = []
    for u, name in zip(utts, names):
        xmin, xmax, tiers = utterance_tiers(manifold, table, u.id)
        tiers = list(tiers) + [gesture_tier(gs, u.id) for gs in gesture_sets]
        out.append(write_textgrid(d / name, xmin, xmax, tiers))
    return out
