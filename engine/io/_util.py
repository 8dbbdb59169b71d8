"""Helpers shared by the importers: decoding text, located number parsing, gap filling,
fitting an alignment to a track."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from engine.corpus import PhoneInterval
from engine.io.errors import ImportFormatError

__all__ = [
    "read_bytes", "decode_text", "parse_floats", "fill_gaps", "fit_phones",
    "natural_key", "check_rate", "sidecar_audio", "one_utterance_corpus", "uniform_rate",
]

def read_bytes(path) -> bytes:
    """All bytes of ``path``; FileNotFoundError when it does not exist."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if path.is_dir():
        raise ImportFormatError(path, "is a directory; expected a file")
    if not path.is_file():  # a FIFO or device would block or never end
        raise ImportFormatError(path, "is not a regular file (a pipe, socket or device); expected a file on disk")
    return path.read_bytes()


def decode_text(data: bytes, path) -> str:
    """Decode a text file: UTF-8 (with or without BOM) or UTF-16 with a BOM.

    Raises :class:`ImportFormatError` naming the line of the first undecodable
    byte, or of a NUL byte (a binary file given where text was expected).
    """
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        try:
            text = data.decode("utf-16")
        except UnicodeDecodeError as exc:
            raise ImportFormatError(path, f"not valid UTF-16 text at byte {exc.start}") from None
    else:
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            line = data[: exc.start].count(b"\n") + 1
            raise ImportFormatError(
                path, f"byte {exc.start} (0x{data[exc.start]:02x}) is not UTF-8 text; expected a text file",
                line=line) from None
    nul = text.find("\0")
    if nul >= 0:
        raise ImportFormatError(path, "contains a NUL character: this is a binary file, expected text",
                                line=text.count("\n", 0, nul) + 1)
    return text


def parse_floats(tokens, path, line: int, what: str = "a number") -> list[float]:
    """Floats from string tokens; a bad token raises an error naming the line and column."""
    out = []
    for k, tok in enumerate(tokens):
        try:
            out.append(float(tok))
        except ValueError:
            raise ImportFormatError(path, f"column {k + 1} is {tok[:40]!r}; expected {what}", line=line) from None
    return out


def fill_gaps(X: np.ndarray, missing: np.ndarray, *, path, names=None, fill: bool = True) -> np.ndarray:
    """Linearly interpolate missing samples per column; hold the edge values.

    Parameters
    ----------
    X : ndarray of shape (n_frames, n_columns)
    missing : bool ndarray of shape (n_frames, n_columns) or (n_frames,)
        True where a sample is absent (dropout, invalid flag, NaN).
    path : str
        File named in errors.
    names : sequence of str, optional
        Column names for errors.
    fill : bool
        If False, any missing sample is an error naming its frame.

    Returns
    -------
    ndarray of shape (n_frames, n_columns), float32, with no missing samples.
    """
    with np.errstate(over="ignore", invalid="ignore"):  # out-of-range values become inf: missing
        X = np.asarray(X).astype(np.float32, copy=False)
    missing = np.asarray(missing, dtype=bool)
    if missing.ndim == 1:
        missing = np.broadcast_to(missing[:, None], X.shape)
    missing = missing | ~np.isfinite(X)
    if not missing.any():
        return X
    X = X.copy()
    cols = np.flatnonzero(missing.any(axis=0))
    for j in cols:
        col_name = names[j] if names is not None else f"column {j}"
        if not fill:
            i = int(np.flatnonzero(missing[:, j])[0])
            raise ImportFormatError(path, f"{col_name} is missing (invalid or not finite); pass fill_gaps=True "
                                    "to interpolate over dropouts", frame=i)
        ok = ~missing[:, j]
        if not ok.any():
            raise ImportFormatError(path, f"{col_name} is missing in every frame; expected at least one valid "
                                    "sample (choose other points/sensors)")
        idx = np.arange(X.shape[0])
        X[:, j] = np.interp(idx, idx[ok], X[ok, j].astype(np.float64))
    return X


#: pause labels of common aligners: a trailing pause past the data is cut without a word
_PAUSES = frozenset({"sil", "sp", "spn", "pau", "#", "h#", "<sil>", "silence", "_", "<p:>", "breath"})
#: an alignment's speech running past the data by more than this (s) is cut with a warning ...
ALIGNMENT_OVERRUN_WARN = 0.1
#: ... and one this many times longer than the data (and 1 s past it) is refused
ALIGNMENT_OVERRUN_RATIO = 2.0


def fit_phones(phones, n_frames: int, rate: float, *, path=None) -> tuple[PhoneInterval, ...]:
    """Fit an alignment to a track of ``n_frames`` at ``rate`` Hz.

    Phones starting at or after the end of the data are dropped, phones running past it
    are cut at it, zero-length phones and unlabelled intervals are dropped. Times stay
    in seconds from the utterance start.

    An alignment whose speech (phones other than pauses) ends more than
    :data:`ALIGNMENT_OVERRUN_WARN` s after the data is
    cut with an :class:`~engine.io.errors.ImportDataWarning` naming both durations; one
    :data:`ALIGNMENT_OVERRUN_RATIO` times as long as the data (and over 1 s longer) is
    refused with an :class:`ImportFormatError` naming ``path`` (a different
    recording's alignment, or a wrong frame rate).
    """
    dur = n_frames / float(rate)
    labelled = [(float(p.start), float(p.end)) for p in phones
                if str(p.label).strip() and str(p.label).strip().lower() not in _PAUSES]
    end = max((e for _, e in labelled), default=0.0)
    if end > dur + ALIGNMENT_OVERRUN_WARN:
        lost = sum(1 for s, _ in labelled if s >= dur)
        what = (f"the alignment runs to {end:.3f} s but the data last {dur:.3f} s ({n_frames} frames at "
                f"{float(rate):g} Hz)")
        if end > ALIGNMENT_OVERRUN_RATIO * dur and end > dur + 1.0:
            raise ImportFormatError(path if path is not None else "<alignment>",
                                    f"{what}: {end / dur:.1f} times as long. Is it this recording's alignment, "
                                    "and is the frame rate right?")
        import warnings

        from engine.io.errors import ImportDataWarning

        where = f"{path}: " if path is not None else ""
        warnings.warn(ImportDataWarning(
            f"{where}{what}; it was cut at the end of the data ({lost} phone{'s' * (lost != 1)} dropped)"),
            stacklevel=2)
    out = []
    for p in phones:
        s, e, lab = float(p.start), float(p.end), str(p.label).strip()
        if not lab or s >= dur:
            continue
        e = min(e, dur)
        s = max(s, 0.0)
        if e > s:
            out.append(PhoneInterval(s, e, lab))
    return tuple(out)


_NUM = re.compile(r"(\d+)")


def natural_key(name: str):
    """Sort key ordering ``f2`` before ``f10``."""
    return [int(t) if t.isdigit() else t.lower() for t in _NUM.split(name)]


def check_rate(path, native: float, rate) -> float:
    """Return the file's ``native`` rate; a different explicit ``rate`` is an error."""
    if rate is not None and abs(float(rate) - native) > 1e-6 * native:
        raise ImportFormatError(
            path, f"the file says its frame rate is {native:g} Hz but rate={float(rate):g} was given; the rate "
            "argument is only for files without timing. To change the rate, resample it "
            "('lipspace import --resample HZ')")
    return float(native)


def sidecar_audio(path) -> str | None:
    """``<stem>.wav`` beside ``path`` if it exists."""
    for suf in (".wav", ".WAV"):
        cand = Path(path).with_suffix(suf)
        if cand.is_file():
            return str(cand)
    return None


def one_utterance_corpus(path, frames, rate, *, dims, uid=None, phones=(), point_names=None, faces=None,
                         audio=None, text="", name=None, units="mm"):
    """A :class:`Corpus` of one utterance read from ``path``; phones fitted to the data.

    ``units``: of the coordinates ("mm", or "" when the file's units are not known).

    Any violated corpus invariant is reported as an :class:`ImportFormatError` naming ``path``.
    """
    from engine.corpus import Corpus, CorpusError, Utterance

    frames = np.asarray(frames, dtype=np.float32)
    if frames.ndim != 2 or frames.shape[0] < 2:
        n = frames.shape[0] if frames.ndim else 0
        raise ImportFormatError(path, f"holds {n} frame{'s' * (n != 1)}; expected at least 2")
    uid = uid or Path(path).stem or "utt"
    try:
        utt = Utterance(uid, 0, frames.shape[0], fit_phones(phones, frames.shape[0], rate, path=path), audio,
                      text)
        return Corpus(frames=frames, rate=rate, utterances=[utt], dims=dims, faces=faces,
                      point_names=point_names, name=name or uid, units=units)
    except CorpusError as exc:
        raise ImportFormatError(path, str(exc)) from None


def uniform_rate(times, path, *, tolerance: float = 0.05) -> float:
    """Frame rate (Hz) from a column of frame times; the spacing must be uniform.

    A step differing from the median step by more than ``tolerance`` of it is an
    error naming the frame. The rate is 1 / the mean step (robust to times rounded to
    the millisecond, as OpenFace writes them); within 0.1% of an integer it is rounded.
    """
    t = np.asarray(times, dtype=np.float64)
    if t.size < 2:
        raise ImportFormatError(path, f"has {t.size} frame time(s); expected at least 2 to tell the frame rate")
    if not np.isfinite(t).all():
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise ImportFormatError(path, f"frame time is {t[i]}; expected a finite number of seconds", frame=i)
    d = np.diff(t)
    step = float(np.median(d))
    if not step > 0:
        raise ImportFormatError(path, f"frame times do not increase (median step {step:g} s); expected "
                                "increasing times in seconds")
    bad = np.flatnonzero(np.abs(d - step) > tolerance * step)
    if bad.size:
        i = int(bad[0]) + 1
        raise ImportFormatError(path, f"frame time {t[i]:g} s follows {t[i - 1]:g} s: a step of {d[i - 1]:g} s "
                                f"where the file's frame step is {step:g} s; expected uniformly spaced frames "
                                "(dropped or repeated frames?)", frame=i)
    rate = (t.size - 1) / float(t[-1] - t[0])  # mean step: robust to times rounded to the millisecond
    r = round(rate)
    return float(r) if r > 0 and abs(rate - r) <= 1e-3 * r else rate
