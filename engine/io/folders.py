"""A lab's folder as import inputs: which of its files are the recordings, in which order, what is left.

``lipspace import corpus/ ...`` reads every recording of a folder, one utterance each:

* the recordings are the files of one data format: the format given (``--format``, or a
  ``--layout``'s), else the one the extensions say, binary formats (``.pos``, ``.mat``,
  ``.ema``, ``.c3d``, ``.npy``, ``.npz``) before text tables (``.csv``, ``.tsv``, ``.txt``),
  then the most frequent; when a format accepts several extensions present, the same
  order decides;
* in natural order of their paths (``utt2`` before ``utt10``); subfolders are read only
  with ``recursive`` (``--recursive``);
* a file's companions (``<stem>.TextGrid`` / ``.lab`` / ``.phn`` alignments and
  ``<stem>.wav`` audio) are used by the readers; every other file, hidden ones and
  subfolders not read are listed in :attr:`FolderInputs.skipped` and said;
* recordings in different subfolders with the same stem get their path (``S1/utt01``)
  as utterance id, so that ids stay unique.

A folder of mesh frames (``.obj`` / ``.ply``) stays one utterance and a folder of videos
stays one speaker's clips (their readers take the folder itself); with ``recursive``, a
folder whose recordings are such subfolders gives one input per subfolder.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from engine.io.errors import ImportFormatError

__all__ = ["FolderInputs", "expand_folders", "FORMAT_EXTENSIONS", "COMPANION_EXTENSIONS"]

#: extensions each format reads in a folder
FORMAT_EXTENSIONS = {
    "pos": (".pos",), "wave": (".tsv", ".txt"), "ema": (".ema",), "mview": (".mat",), "c3d": (".c3d",),
    "csv": (".csv", ".tsv", ".txt"), "npy": (".npy",), "npz": (".npz",),
    "matrix": (".pos", ".mat", ".npy", ".csv", ".tsv", ".txt"),
}
#: files read beside a recording of the same stem
COMPANION_EXTENSIONS = (".textgrid", ".lab", ".phn", ".wav")
_BINARY = (".pos", ".mat", ".ema", ".c3d", ".npy", ".npz")
_KEEP_WHOLE = ("mesh", "video")


@dataclass
class FolderInputs:
    """The inputs after folders were expanded.

    Attributes
    ----------
    paths : list of str
        Every input, a folder's recordings in place of the folder.
    ids : dict of str to str
        Utterance id of a recording whose stem another recording shares.
    roots : dict of str to str
        The folder each recording was found in (for metadata tables keyed by relative path).
    skipped : list of (str, str)
        Files and folders left out, with why.
    notes : list of str
        One sentence per folder: how many recordings, of which format, what was left out.
    """

    paths: list = field(default_factory=list)
    ids: dict = field(default_factory=dict)
    roots: dict = field(default_factory=dict)
    skipped: list = field(default_factory=list)
    notes: list = field(default_factory=list)


def _natural(p: Path, root: Path):
    from engine.io._util import natural_key

    return natural_key(p.relative_to(root).as_posix())


def _walk(root: Path, recursive: bool):
    """(files, skipped): every regular file under ``root`` (hidden ones and, without ``recursive``, subfolders
    skipped)."""
    files, skipped = [], []
    for p in sorted(root.iterdir(), key=lambda q: _natural(q, root)):
        if p.name.startswith("."):
            skipped.append((str(p), "hidden"))
        elif p.is_dir():
            if recursive:
                f, s = _walk(p, True)
                files += f
                skipped += s
            else:
                skipped.append((str(p), "a subfolder (give --recursive to read subfolders)"))
        elif p.is_file():
            files.append(p)
        else:
            skipped.append((str(p), "not a regular file"))
    return files, skipped


def _folder_format(files, fmt) -> tuple[str | None, str | None]:
    """(format, extension) of a folder's recordings; (None, None) when none of its files is a recording."""
    from engine.io.dispatch import _EXT

    exts: dict[str, int] = {}
    for f in files:
        exts[f.suffix.lower()] = exts.get(f.suffix.lower(), 0) + 1

    def best(candidates):
        present = [e for e in candidates if e in exts]
        if not present:
            return None
        return sorted(present, key=lambda e: (e not in _BINARY, -exts[e], e))[0]

    if fmt is not None:
        return fmt, best(FORMAT_EXTENSIONS.get(fmt, ()))
    data = [e for e in exts if e in _EXT and e not in COMPANION_EXTENSIONS and _EXT[e] not in _KEEP_WHOLE]
    ext = best(data)
    return (_EXT[ext], ext) if ext else (None, None)


def expand_folders(inputs, *, format: str | None = None, recursive: bool = False) -> FolderInputs:
    """Replace every folder among ``inputs`` by its recordings (module docstring).

    Parameters
    ----------
    inputs : sequence of str or Path
    format : str, optional
        The data format (``--format``, or ``matrix`` / ``pos`` / ``wave`` for a layout).
    recursive : bool

    Returns
    -------
    FolderInputs

    Raises
    ------
    ImportFormatError
        A folder holding no recording of the format (naming what it holds).
    """
    out = FolderInputs()
    for item in map(Path, map(str, inputs)):
        if not item.is_dir():
            out.paths.append(str(item))
            continue
        if format in _KEEP_WHOLE or (format is None and _whole(item)):
            out.paths.append(str(item))  # a mesh sequence, or one speaker's videos: their readers take the folder
            continue
        subs = _whole_subfolders(item, format) if recursive else []
        if subs:  # one mesh sequence (or one speaker's videos) per subfolder
            out.paths += [str(d) for d in subs]
            shown = ", ".join(d.name for d in subs[:4]) + (" ..." if len(subs) > 4 else "")
            out.notes.append(f"{item}: {len(subs)} subfolders read as one recording each ({shown})")
            continue
        files, skipped = _walk(item, recursive)
        fmt, ext = _folder_format(files, format)
        if ext is None:
            kinds = sorted({f.suffix.lower() or "(no extension)" for f in files})
            want = f"{format} recordings ({', '.join(FORMAT_EXTENSIONS.get(format, ()))})" if format else \
                "recordings of a format lipspace import reads"
            sub = f" and {sum(1 for _, why in skipped if why.startswith('a subfolder'))} subfolders" if \
                any(why.startswith("a subfolder") for _, why in skipped) else ""
            raise ImportFormatError(item, f"holds no {want}: {len(files)} files ({', '.join(kinds[:8]) or 'none'})"
                                    f"{sub}")
        rec = [f for f in files if f.suffix.lower() == ext]
        stems = {f.with_suffix("").name for f in rec}
        for f in files:
            if f.suffix.lower() == ext:
                continue
            if f.suffix.lower() in COMPANION_EXTENSIONS and f.with_suffix("").name in stems:
                continue
            skipped.append((str(f), f"not a {ext} recording"))
        seen: dict[str, int] = {}
        for f in rec:
            seen[f.stem] = seen.get(f.stem, 0) + 1
        for f in rec:
            out.paths.append(str(f))
            out.roots[str(f)] = str(item)
            if seen[f.stem] > 1:
                out.ids[str(f)] = f.relative_to(item).with_suffix("").as_posix()
        out.skipped += skipped
        left = [Path(p).name for p, why in skipped if str(Path(p).parent).startswith(str(item))]
        note = (f"{item}: {len(rec)} {ext} recording{'s' * (len(rec) != 1)} ({fmt}) in natural order"
                + (", subfolders included" if recursive else ""))
        if left:
            note += f"; left out {len(left)}: {', '.join(left[:6])}{' ...' if len(left) > 6 else ''}"
        out.notes.append(note)
    return out


def _whole_subfolders(folder: Path, format) -> list:
    """The subfolders of ``folder`` that are each read whole (mesh frames, videos), when its recordings are all in
    such subfolders; [] otherwise."""
    if format not in (None, *_KEEP_WHOLE):
        return []
    from engine.io.dispatch import _EXT

    direct = [f for f in folder.iterdir() if f.is_file() and _EXT.get(f.suffix.lower()) is not None]
    subs = sorted((d for d in folder.iterdir() if d.is_dir() and not d.name.startswith(".")),
                  key=lambda d: _natural(d, folder))
    whole = [d for d in subs if _whole(d)]
    return whole if whole and not direct else []


def _whole(folder: Path) -> bool:
    """Whether a folder is read whole by its reader: mesh frames or videos directly inside, no other recording."""
    from engine.io.dispatch import _EXT

    kinds = {_EXT.get(f.suffix.lower()) for f in folder.iterdir() if f.is_file() and not f.name.startswith(".")}
    kinds.discard(None)
    kinds -= {_EXT.get(e) for e in COMPANION_EXTENSIONS}
    return bool(kinds) and kinds <= set(_KEEP_WHOLE)
