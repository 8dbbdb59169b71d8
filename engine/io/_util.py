"""Helpers shared by the importers: decoding text, located number parsing, gap filling,
fitting an alignment to a track."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from engine.io.errors import ImportFormatError
from engine.recordings.corpus import PhoneInterval

__all__ = [
    "read_bytes", "decode_text", "parse_floats", "fill_gaps", "fit_phones",
    "natural_key", "check_rate", "plausible_rate", "sidecar_audio", "one_utterance_corpus", "uniform_rate",
]

def read_bytes(path, *, expansion: int | None = None) -> bytes:
    """All bytes of ``path``; FileNotFoundError when it does not exist.

    Only a regular file is read (a FIFO or device would block or never end), and only when
    ``expansion`` times its size fits in the memory this process may use
    (:func:`engine.files.bounded.input_limit`; default: a text table's expansion): a 6 GB
    file is refused naming its size and the limit before a byte is read.
    """
    from engine.files.bounded import TEXT_EXPANSION, InputTooLargeError, NotRegularFileError, input_limit, read_bounded

    path = Path(path)
    limit, why = input_limit(TEXT_EXPANSION if expansion is None else expansion)
    try:
        return read_bounded(path, limit=limit, why=why)
    except NotRegularFileError as exc:
        raise ImportFormatError(path, f"is {exc.kind}, not a regular file; expected a file on disk") from None
    except InputTooLargeError as exc:
        raise ImportFormatError(path, f"{str(exc).removeprefix(f'{path}: ')}. Split the recording into several "
                                "files") from None


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


#: a kept column may be missing in at most this share of its frames to be interpolated; more is refused
MAX_FILL_FRACTION = 0.5
#: coordinates larger than this in magnitude are implausible in any unit lips are recorded in (mm,
#: cm, m, pixels): a sentinel, an overflowed or a damaged sample. They are dropouts.
IMPLAUSIBLE_COORDINATE = 1e6


def fill_gaps(X: np.ndarray, missing: np.ndarray, *, path, names=None, fill: bool = True,
              flagged: str = "flagged invalid", nan: str = "NaN", first_frame: int = 0) -> np.ndarray:
    """Linearly interpolate missing samples per column, hold the edge values, and report it.

    A sample is missing when ``missing`` flags it (a break flag, an invalid marker, a
    status that is not OK), when it is not finite, or when its magnitude exceeds
    :data:`IMPLAUSIBLE_COORDINATE`. The repair is reported per file
    (:func:`engine.io.repairs.report_repair`): how many samples of which columns, why,
    in which frames, and how they were filled.

    Parameters
    ----------
    X : ndarray of shape (n_frames, n_columns)
    missing : bool ndarray of shape (n_frames, n_columns) or (n_frames,)
        True where the file marks a sample absent.
    path : str
        File named in errors and in the report.
    names : sequence of str or callable(int) -> str, optional
        Column names (default ``column <j>``).
    fill : bool
        If False, any missing sample is an error naming its column and frame.
    flagged, nan : str
        How the report names samples ``missing`` flags and NaN samples (e.g. ``"break
        flag 0"``, ``"empty or NaN"``).
    first_frame : int
        The number of the first row, for the frames the report and errors name (a table
        that numbers its frames gives its own numbers; default: 0-based rows).

    Returns
    -------
    ndarray of shape (n_frames, n_columns), float32, with no missing samples.

    Raises
    ------
    ImportFormatError
        A column missing in every frame, or in more than :data:`MAX_FILL_FRACTION` of its
        frames; any missing sample when ``fill`` is False.
    """
    from engine.io.repairs import frame_runs, report_repair

    with np.errstate(over="ignore", invalid="ignore"):  # out-of-range values become inf: missing
        X = np.asarray(X).astype(np.float32, copy=False)
    flag = np.asarray(missing, dtype=bool)
    if flag.ndim == 1:
        flag = np.broadcast_to(flag[:, None], X.shape)
    finite = np.isfinite(X)
    with np.errstate(invalid="ignore"):
        huge = finite & (np.abs(X) > IMPLAUSIBLE_COORDINATE)
    miss = flag | ~finite | huge
    if not miss.any():
        return X

    def name(j):
        if names is None:
            return f"column {j}"
        return names(j) if callable(names) else names[j]

    nan_mask, inf_mask = np.isnan(X), np.isinf(X)

    def why(j=slice(None)):
        """What the missing samples of column(s) ``j`` are, counted by cause."""
        m, f = miss[:, j], flag[:, j]
        kinds = [(int((m & f).sum()), flagged), (int((m & ~f & nan_mask[:, j]).sum()), nan),
                 (int((m & ~f & inf_mask[:, j]).sum()), "infinite"),
                 (int((m & ~f & huge[:, j]).sum()), f"implausibly large (beyond {IMPLAUSIBLE_COORDINATE:g})")]
        return ", ".join(f"{k} {w}" for k, w in kinds if k)

    n = X.shape[0]
    cols = np.flatnonzero(miss.any(axis=0))
    for j in cols:
        rows = np.flatnonzero(miss[:, j])
        i = int(rows[0])
        if not fill:
            raise ImportFormatError(path, f"{name(j)} is missing ({why(j)} in {rows.size} of {n} "
                                    "frames); refused because gap filling is off (import without --no-fill to "
                                    "interpolate dropouts)", frame=i + first_frame)
        if rows.size == n:
            raise ImportFormatError(path, f"{name(j)} is missing in every frame ({why(j)}); expected "
                                    "at least one valid sample (choose other points or sensors with --points)")
        if rows.size > MAX_FILL_FRACTION * n:
            raise ImportFormatError(path, f"{name(j)} is missing in {rows.size} of {n} frames "
                                    f"({100 * rows.size / n:.0f}%: {why(j)}); at most "
                                    f"{100 * MAX_FILL_FRACTION:.0f}% of a channel can be interpolated. Leave it out "
                                    "(--points) or check the recording", frame=i + first_frame)
    X = X.copy()
    idx = np.arange(n)
    for j in cols:
        ok = ~miss[:, j]
        X[:, j] = np.interp(idx, idx[ok], X[ok, j].astype(np.float64))
    rows = np.flatnonzero(miss.any(axis=1))
    shown = [name(j) for j in cols[:6]]
    more = f" and {cols.size - 6} more" if cols.size > 6 else ""
    edge = " (a column missing at the start or the end holds its first or last valid value)" if \
        miss[0].any() or miss[-1].any() else ""
    report_repair(path, f"{int(miss.sum())} missing samples ({why()}) in {', '.join(shown)}{more}, in "
                  f"{rows.size} of {n} frames ({frame_runs(rows + first_frame)}); interpolated linearly between the "
                  f"nearest valid frames{edge}")
    return X


#: pause labels of common aligners: a trailing pause past the data is cut with a note, never refused
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
    cut and reported (:func:`engine.io.repairs.report_repair`) naming both durations; one
    :data:`ALIGNMENT_OVERRUN_RATIO` times as long as the data (and over 1 s longer) is
    refused with an :class:`ImportFormatError` naming ``path`` (a different
    recording's alignment, or a wrong frame rate). One that runs past the data by less, or
    only with a pause (MOCHA's final silence), is cut and reported too: the user is told
    where the utterance ends.
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
        from engine.io.repairs import report_repair

        report_repair(path, f"{what}; it was cut at the end of the data ({lost} phone{'s' * (lost != 1)} dropped)")
    else:  # a pause (or speech by less than the warning's margin) past the data: cut, and said
        last = max(((float(p.end), str(p.label).strip()) for p in phones if str(p.label).strip()), default=None)
        if last is not None and last[0] > dur + 0.5 / float(rate):
            from engine.io.repairs import report_repair

            report_repair(path, f"the alignment runs to {last[0]:.3f} s but the data last {dur:.3f} s ({n_frames} "
                                f"frames at {float(rate):g} Hz); it was cut at the end of the data (its last "
                                f"interval, {last[1]!r}, ends there)")
    out, empty = [], []
    for p in phones:
        s, e, lab = float(p.start), float(p.end), str(p.label).strip()
        if not lab or s >= dur:
            continue
        e = min(e, dur)
        s = max(s, 0.0)
        if e > s:
            out.append(PhoneInterval(s, e, lab))
        elif lab.lower() not in _PAUSES:
            empty.append(f"{lab} at {s:.3f} s")
    if empty:  # a labelled phone of no duration has no frame to stand for: dropped, and said
        from engine.io.repairs import report_repair

        report_repair(path, f"{len(empty)} phone{'s' * (len(empty) != 1)} of zero duration dropped from the "
                      f"alignment ({', '.join(empty[:5])}{', ...' if len(empty) > 5 else ''})")
    return tuple(out)


_NUM = re.compile(r"(\d+)")


def natural_key(name: str):
    """Sort key ordering ``f2`` before ``f10``."""
    return [int(t) if t.isdigit() else t.lower() for t in _NUM.split(name)]


#: frame rates (Hz) lip motion is recorded at: webcams from 10 fps, articulographs and motion capture up
#: to a few kHz, high-speed video below 20 kHz. A rate outside is a damaged or misread header.
MOTION_RATE_RANGE = (10.0, 20000.0)
#: sample rates (Hz) of speech audio
AUDIO_RATE_RANGE = (1000.0, 768000.0)


def plausible_rate(path, value, field: str, *, line: int | None = None, audio: bool = False) -> float:
    """``value`` as a rate in Hz, or an :class:`ImportFormatError` naming ``field`` (a header field,
    a variable, an option) when it is not a number, not finite, not positive or outside
    :data:`MOTION_RATE_RANGE` (:data:`AUDIO_RATE_RANGE` for ``audio``)."""
    lo, hi = AUDIO_RATE_RANGE if audio else MOTION_RATE_RANGE
    what = "a sample rate" if audio else "a frame rate"
    try:
        r = float(value)
    except (TypeError, ValueError):
        raise ImportFormatError(path, f"{field} is {str(value)[:30]!r}; expected {what} in Hz", line=line) from None
    if not (np.isfinite(r) and r > 0):
        raise ImportFormatError(path, f"{field} is {r:g}; expected {what} in Hz, a positive number", line=line)
    if not lo <= r <= hi:
        raise ImportFormatError(path, f"{field} is {r:g} Hz; {what} of {'speech audio' if audio else 'lip motion'} "
                                f"is from {lo:g} to {hi:g} Hz (a damaged header, or times in other units?)",
                                line=line)
    return r


def check_rate(path, native: float, rate) -> float:
    """Return the file's ``native`` rate; a different explicit ``rate`` is an error."""
    if rate is not None and abs(float(rate) - native) > 1e-6 * native:
        raise ImportFormatError(
            path, f"the file says its frame rate is {native:g} Hz but a rate of {float(rate):g} Hz was given "
            "(--rate); a rate is only given for files without timing. To change the rate, resample "
            "('lipspace import --resample HZ')")
    return float(native)


def sidecar_audio(path) -> str | None:
    """``<stem>.wav`` beside ``path`` when it is a WAV file (its header checked). One that is not is
    left unlinked and said (:func:`engine.io.repairs.report_repair`: the corpus history, a warning);
    one that is linked is named in the history by :func:`one_utterance_corpus`."""
    from engine.files.validate import wav_info
    from engine.io.repairs import report_repair

    for suf in (".wav", ".WAV"):
        cand = Path(path).with_suffix(suf)
        if cand.is_file():
            try:
                wav_info(cand)  # raises on a file that is not a readable WAV
            except (OSError, ValueError) as exc:
                report_repair(path, f"{cand.name} beside it was not linked as its audio: "
                              f"{str(exc).removeprefix(f'{cand}: ')}")
                return None
            return str(cand)  # said in the corpus history (one_utterance_corpus)
    return None


def one_utterance_corpus(path, frames, rate, *, dims, uid=None, phones=(), point_names=None, faces=None,
                         audio=None, text="", name=None, units="mm"):
    """A :class:`Corpus` of one utterance read from ``path``; phones fitted to the data.

    ``units``: of the coordinates ("mm", or "" when the file's units are not known).

    Any violated corpus invariant is reported as an :class:`ImportFormatError` naming ``path``.
    """
    from engine.recordings.corpus import Corpus, CorpusError, Utterance

    frames = np.asarray(frames, dtype=np.float32)
    if frames.ndim != 2 or frames.shape[0] < 2:
        n = frames.shape[0] if frames.ndim else 0
        raise ImportFormatError(path, f"holds {n} frame{'s' * (n != 1)}; expected at least 2")
    uid = uid or Path(path).stem or "utt"
    try:
        utt = Utterance(uid, 0, frames.shape[0], fit_phones(phones, frames.shape[0], rate, path=path), audio,
                      text)
        said = [f"{Path(path).name}: audio {Path(audio).name} linked"] if audio else []  # never linked unsaid
        return Corpus(frames=frames, rate=rate, utterances=[utt], dims=dims, faces=faces,
                      point_names=point_names, name=name or uid, units=units, history=said)
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
    rate = float(r) if r > 0 and abs(rate - r) <= 1e-3 * r else rate
    return plausible_rate(path, rate, f"the frame times (a step of {step:g} s) give a rate that")
