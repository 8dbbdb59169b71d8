"""A one-utterance 3-D corpus from a numeric matrix read through a sensor layout.

Shared by the plain-matrix reader (:mod:`engine.io.readers.matrix`) and the articulograph
readers (:mod:`engine.io.readers.articulograph`), which both import it from here (they no
longer import each other).
"""
from __future__ import annotations

import numpy as np

from engine.io._util import fill_gaps as _fill_gaps
from engine.io._util import one_utterance_corpus, sidecar_audio
from engine.io.errors import ImportFormatError
from engine.io.readers.alignment import resolve_alignment
from engine.recordings.layouts import LayoutError

__all__ = ["corpus_from_matrix"]


def corpus_from_matrix(path, M, layout, *, rate: float, points=None, fill_gaps: bool = True, alignment=None,
                       tier=None, missing=None, flagged: str = "flagged invalid", quality=None,
                       quality_measure: str = "rms"):
    """A one-utterance 3-D corpus from a matrix (n_frames, n_sensors * values) read through ``layout``.

    Parameters
    ----------
    path : str or Path
        The file the matrix came from (named in errors; finds a sidecar alignment / audio).
    M : ndarray of shape (n_frames, layout.n_columns)
    layout : Layout
    rate : float
    points : None, "all", "lips" or sequence of str
        Sensors to keep (:meth:`engine.recordings.layouts.Layout.select`).
    fill_gaps : bool
    missing : bool ndarray of shape (n_frames, n_sensors), optional
        Samples flagged invalid by the file (besides NaN).
    flagged : str
        How the repair report names the samples ``missing`` flags (e.g. "status not OK").
    quality : ndarray of shape (n_frames, n_sensors), optional
        Each sensor's quality value per frame (default: the layout's ``quality`` value of
        each sensor, when it names one); kept as ``latent["quality_<quality_measure>"]``
        (:mod:`engine.recordings.signals.quality`), out-of-range values reported.
    quality_measure : str
        What the quality values are (``"rms"``, ``"error"``).

    Returns
    -------
    Corpus
        Frames (n, 3 * n_kept) in the file's units; ``point_names`` and ``point_roles``
        from the layout.
    """
    M = np.asarray(M)
    if M.ndim != 2:
        raise ImportFormatError(path, f"holds an array of shape {M.shape}; expected a 2-D matrix (frames, columns)")
    if not np.issubdtype(M.dtype, np.number) or np.iscomplexobj(M):
        raise ImportFormatError(path, f"holds {M.dtype} values; expected real numbers")
    if M.shape[1] != layout.n_columns:
        per, cols = layout.values, M.shape[1]
        fits = [f"{cols // v} sensors x {v} values" for v in dict.fromkeys((per, 7, 6)) if cols % v == 0]
        from engine.recordings.layouts import BUILTIN

        same = [n for n, lay in BUILTIN.items() if lay.format == "matrix" and lay.n_columns == cols]
        hint = (f" ({cols} = {' or '.join(fits)}: give a layout with that shape"
                f"{', e.g. ' + ', '.join(same) if same else ''})") if fits else ""
        raise ImportFormatError(path, f"has {M.shape[1]} columns but layout {layout.name!r} expects "
                                f"{len(layout.sensors)} sensors x {per} values = {layout.n_columns}{hint}")
    try:
        keep = layout.select(points)
    except LayoutError as exc:
        raise ImportFormatError(path, str(exc)) from None
    n = M.shape[0]
    block = M.reshape(n, len(layout.sensors), layout.values)
    X = block[:, keep][:, :, list(layout.xyz)].reshape(n, -1)
    miss = np.zeros(X.shape, bool)  # NaN and implausible samples are found by fill_gaps
    if missing is not None:
        miss |= np.repeat(np.asarray(missing, bool)[:, keep], 3, axis=1)
    names = [layout.sensors[i] for i in keep]
    cols = [f"{s}_{a}" for s in names for a in "xyz"]
    with np.errstate(invalid="ignore"):
        invalid = (miss | ~np.isfinite(X)).reshape(n, len(keep), 3).any(axis=2)  # no position: no quality
    frames = _fill_gaps(X, miss, path=path, names=cols, fill=fill_gaps, flagged=flagged)
    phones, _ = resolve_alignment(path, alignment, tier=tier)
    c = one_utterance_corpus(path, frames, rate, dims=3, phones=phones, point_names=names,
                             audio=sidecar_audio(path))
    roles = [layout.roles[i] for i in keep]
    c.point_roles = roles if any(roles) else None
    if quality is None and layout.quality is not None:
        quality = block[:, :, layout.quality]
    if quality is not None:
        c.latent[f"quality_{quality_measure}"] = checked_quality(path, np.asarray(quality)[:, keep], names,
                                                                 quality_measure, invalid)
    return c


def checked_quality(path, Q, names, measure: str, missing) -> np.ndarray:
    """Quality values ``Q`` (n_frames, n_sensors) as stored (float32; 0 = not measured), the out-of-range ones
    (negative, NaN or infinite where the position is valid) reported naming the sensor and frames and stored as
    not measured."""
    from engine.io.repairs import frame_runs, report_repair

    with np.errstate(over="ignore", invalid="ignore"):
        Q = np.asarray(Q, dtype=np.float64)
    bad = (~np.isfinite(Q) | (Q < 0)) & ~np.asarray(missing, bool)
    for j in np.flatnonzero(bad.any(axis=0)):
        rows = np.flatnonzero(bad[:, j])
        report_repair(path, f"{names[j]} {measure} is out of range ({Q[rows[0], j]:g} in "
                      f"{frame_runs(rows)}; expected a number >= 0); those {rows.size} quality values are taken as "
                      "not measured (the positions are kept)")
    Q = np.where(bad | ~np.isfinite(Q) | np.asarray(missing, bool), 0.0, Q)
    return Q.astype(np.float32)
