"""The bad-input campaign's case record and the helpers that write damaged inputs (shared by the case lists)."""
from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _changed_npz(src, dst, **changes) -> Path:
    """A copy of the .npz ``src`` at ``dst`` with the arrays ``changes`` replaced (a damaged or renamed corpus)."""
    import numpy as np

    arrays = {**dict(np.load(src, allow_pickle=False)), **changes}
    with open(dst, "wb") as fh:
        np.savez(fh, **arrays)
    return Path(dst)




@dataclass
class Case:
    """One run: ``argv`` of ``lipspace`` (or ``["@py", code]``, ``["@sh", script]``), the exit expected (0, 1 = a
    Python snippet printing its verdict, 2, None = stopped by a signal or finished, another number: that one),
    what stderr must say. A snippet or script may print ``@@VERDICT WORD`` to give its own verdict; ``after``
    may return ``"LOST: why"`` (or another verdict word and a colon) instead of a plain problem (SILENT)."""

    name: str
    argv: list
    expect: int | None
    says: str | None = None
    gone: list = field(default_factory=list)  # files that must not exist after a failure or a stop
    keep: list = field(default_factory=list)  # user files (path or (path, bytes)) that must stay byte for byte
    mount: str | None = None  # "tmpfs:SIZE" (a full disk) or "ro" at d/"tiny" for the run
    env: dict = field(default_factory=dict)
    never: str | None = None  # text stderr must not hold (a misleading hint)
    after: object = None  # callable(d) -> problem or None, run after the case (e.g. info keeps the repair)
    stop_after: float | None = None  # seconds until SIGTERM (with stop_when: at most)
    stop_when: str | None = None  # SIGTERM as soon as a file matching this glob (below the case folder) exists
    lines: int = 1  # most lines a refusal may print (the unreadable inputs are listed one per line)
    loses_input: bool = False  # exit 0 would mean an input was lost (LOST, not SILENT)
    group: str = ""  # the class of issue 45 it belongs to ("" = the checklist of issues 16 and 30)
    during: object = None  # callable(d), run once while the case runs (at stop_when, or after stop_after s)
    timeout: float | None = None  # seconds before it counts as a hang (default: the campaign's)
    prepare: object = None  # callable(d), run before the case (after the output folder is emptied)




def _old(p, text=b"a user's own file\n"):
    p = Path(p)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_bytes(text)
    return str(p)


def _pos(path, M, rate="250", n_ch=2):
    import numpy as np

    hdr = f"AG50xDATA_V002\n00000000\nNumberOfChannels={n_ch}\nSamplingFrequencyHz={rate}\n".encode()
    hdr = hdr.replace(b"00000000", f"{len(hdr):08d}".encode())
    path.write_bytes(hdr + np.asarray(M, "<f4").tobytes())
    return str(path)


def _mview(path, sig, *, srate=100.0, audio=None, names=("UL", "LL")):
    import numpy as np
    import scipy.io

    dt = [("NAME", "O"), ("SRATE", "O"), ("SIGNAL", "O"), ("SENTENCE", "O"), ("PHONES", "O")]
    s = np.zeros((1, 1 + len(names)), dtype=dt)
    snd = np.random.default_rng(2).normal(size=(4410, 1)) * 0.1 if audio is None else audio
    s[0, 0] = ("AUDIO", 44100.0, snd.astype(np.float32), "", np.zeros((0, 0)))
    for k, n in enumerate(names):
        s[0, 1 + k] = (n, srate, sig.astype(np.float32) + k, "", np.zeros((0, 0)))
    scipy.io.savemat(path, {Path(path).stem: s})
    return str(path)


def _info_says(corpus, text):
    """An ``after`` check: ``lipspace info CORPUS`` lists ``text`` in the history."""
    def check(d, root):
        r = subprocess.run([sys.executable, "-m", "app.cli", "info", str(corpus)], cwd=d, capture_output=True,
                           text=True, env=dict(os.environ, PYTHONPATH=str(root)))
        return None if text in r.stdout else f"info does not keep {text!r} in the history"
    return check
