"""Plain numeric articulograph matrices read through a sensor layout.

A ``.mat`` variable, a ``.npy`` array or a CSV / TSV / whitespace table *without*
column names holds one row per frame and ``values`` numbers per sensor, sensor after
sensor (the layout, :mod:`engine.recordings.layouts`, says which are x, y, z and what each
sensor is). :func:`read_matrix` turns it into a 3-D corpus of the chosen sensors with
their names and roles. Such files carry no timing: the rate comes from ``rate=``, the
layout, or a scalar ``fs`` / ``srate`` / ``rate`` variable beside the matrix in a
``.mat`` file. NaN samples are dropouts, interpolated (or an error with
``fill_gaps=False``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from engine.io._util import decode_text, plausible_rate, read_bytes
from engine.io.errors import ImportFormatError
from engine.io.readers.sensor_matrix import corpus_from_matrix
from engine.io.repairs import reports_repairs
from engine.recordings.layouts import Layout, LayoutError, get_layout

__all__ = ["read_matrix", "corpus_from_matrix", "MATRIX_EXTENSIONS"]

MATRIX_EXTENSIONS = (".mat", ".npy", ".csv", ".tsv", ".txt")
_RATE_NAMES = ("fs", "srate", "samplerate", "sampling_rate", "rate", "sr")


def _rate_of(path, layout: Layout, rate, found=None) -> float:
    r = rate if rate is not None else (found[1] if found is not None else layout.rate)
    if r is None:
        raise ImportFormatError(path, f"a plain matrix carries no timing and layout {layout.name!r} gives no rate; "
                                "give one (lipspace import --rate HZ)")
    field = ("the frame rate given (--rate)" if rate is not None else
             f"variable {found[0]!r}" if found is not None else f"the rate of layout {layout.name!r}")
    return plausible_rate(path, r, field)


def _from_mat(path, variable, notes=None):
    from engine.io.readers.matfile import read_mat

    m = read_mat(path, notes=notes)
    names = [k for k in m if not k.startswith("__")]
    numeric = {k: v for k, v in m.items() if isinstance(v, np.ndarray) and v.ndim == 2 and v.size > 1
               and np.issubdtype(v.dtype, np.number) and min(v.shape) > 1}
    found = None
    for k, v in m.items():
        if k.lower() in _RATE_NAMES and isinstance(v, np.ndarray) and v.size == 1 and \
                np.issubdtype(v.dtype, np.number):
            found = (k, float(np.real(v.ravel()[0])))
    if variable is not None:
        if variable not in m:
            raise ImportFormatError(path, f"has no variable {variable!r}; it has {names[:12]}")
        if variable not in numeric:
            raise ImportFormatError(path, f"variable {variable!r} is not a 2-D numeric matrix")
        return numeric[variable], found
    if len(numeric) != 1:
        desc = ", ".join(f"{k} {v.shape}" for k, v in numeric.items()) or "none"
        raise ImportFormatError(path, f"holds {len(numeric)} 2-D numeric matrices ({desc}); expected one, or name "
                                "it (lipspace import --variable NAME)")
    return next(iter(numeric.values())), found


def _from_text(path):
    text = decode_text(read_bytes(path), path)
    first = next((ln.strip() for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")), "")
    sep = next((c for c in ("\t", ",", ";") if c in first), None)
    try:  # fast path (numpy's C parser); any fault is located by the line-by-line parser below
        import io
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("error")
            M = np.loadtxt(io.StringIO(text), delimiter=sep, comments="#", ndmin=2, dtype=np.float64)
        if M.size:
            return M
    except (ValueError, UserWarning):
        pass
    rows, width = [], None
    for ln, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        sep = next((c for c in ("\t", ",", ";") if c in line), None)
        toks = [t.strip() for t in line.split(sep)] if sep else line.split()
        vals = []
        for k, t in enumerate(toks):
            if t == "" or t.lower() in ("nan", "na"):
                vals.append(np.nan)
                continue
            try:
                vals.append(float(t))
            except ValueError:
                hint = (" — this looks like a header of column names: a named CSV (<name>_x, <name>_y, <name>_z "
                        "columns) is read without --layout") if not rows else ""
                raise ImportFormatError(path, f"column {k + 1} is {t[:40]!r}; expected a number{hint}",
                                        line=ln) from None
        if width is None:
            width = len(vals)
        elif len(vals) != width:
            raise ImportFormatError(path, f"has {len(vals)} values; earlier lines have {width}", line=ln)
        rows.append(vals)
    if not rows:
        raise ImportFormatError(path, "holds no rows of numbers")
    return np.array(rows, dtype=np.float64)


@reports_repairs
def read_matrix(path, *, layout, rate: float | None = None, variable: str | None = None, points=None,
                alignment=None, tier: str | None = None, fill_gaps: bool = True):
    """A plain numeric matrix file (``.mat`` variable, ``.npy``, CSV/TSV without names) through a layout.

    Parameters
    ----------
    path : str or Path
    layout : str, Path or Layout
        Built-in layout name (:data:`engine.recordings.layouts.BUILTIN`) or a user layout file.
    rate : float, optional
        Frame rate (Hz); default: a ``fs``/``srate``/``rate`` scalar in the ``.mat`` file,
        else the layout's rate. Required when neither gives one.
    variable : str, optional
        ``.mat`` variable holding the matrix (default: the only 2-D numeric one).
    points : None, "all", "lips" or sequence of str
        Sensors to keep (default: lip, corner, jaw and reference sensors; every sensor
        when the layout gives no roles).
    alignment, tier : see :func:`engine.io.read_corpus`
    fill_gaps : bool
        Interpolate NaN dropouts (else an error naming the frame).

    Returns
    -------
    Corpus
        One utterance, 3-D, with ``point_names`` and ``point_roles``.
    """
    path = Path(path)
    try:
        lay = get_layout(layout)
    except LayoutError as exc:
        raise ImportFormatError(path, str(exc)) from None
    if lay.format != "matrix":
        from engine.io.readers.articulograph import read_pos, read_wave

        fn = read_pos if lay.format == "pos" else read_wave
        return fn(path, layout=lay, rate=rate, points=points, alignment=alignment, tier=tier, fill_gaps=fill_gaps)
    suf = path.suffix.lower()
    if suf == ".pos":
        raise ImportFormatError(path, f"a .pos file is an AG500/AG501 binary; layout {lay.name!r} describes a plain "
                                "matrix: use layout ag500 or ag501, or a layout file with 'base: ag501'")
    found = None
    damage: list[str] = []
    if suf == ".mat":
        M, found = _from_mat(path, variable, damage)
    elif suf == ".npy":
        read_bytes(path)  # FileNotFoundError / directory errors
        try:
            M = np.load(path, allow_pickle=False)
        except (ValueError, OSError, EOFError) as exc:
            raise ImportFormatError(path, f"not a readable .npy array ({exc})") from None
    else:
        M = _from_text(path)
    if variable is not None and suf != ".mat":
        raise ImportFormatError(path, "--variable applies to .mat files only")
    r = _rate_of(path, lay, rate, found)
    c = corpus_from_matrix(path, M, lay, rate=r, points=points, fill_gaps=fill_gaps, alignment=alignment,
                           tier=tier)
    c.history.extend(f"{path.name}: {d}" for d in damage)  # what a damaged file still gave
    return c
