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
                       tier=None, missing=None, flagged: str = "flagged invalid"):
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
    frames = _fill_gaps(X, miss, path=path, names=cols, fill=fill_gaps, flagged=flagged)
    phones, _ = resolve_alignment(path, alignment, tier=tier)
    c = one_utterance_corpus(path, frames, rate, dims=3, phones=phones, point_names=names,
                             audio=sidecar_audio(path))
    roles = [layout.roles[i] for i in keep]
    c.point_roles = roles if any(roles) else None
    return c
