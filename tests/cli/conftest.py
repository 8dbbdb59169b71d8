"""Fixtures for the command-line tests: a lab's folder of articulograph recordings made the way real ones are."""
from __future__ import annotations

import numpy as np
import pytest

#: letter codes a lab's file names start with (speaker, then session letters), as in ABCFIA01.mat ... XYMNE16.mat
LAB_CODES = {"S1": "ABCFIA", "S2": "KLMFIB", "S3": "XYMNE"}


def write_lab_folder(folder, *, n_utterances=3, duration_s=(1.0, 1.2), seed=5, compress=True):
    """MAT v5 files ``<code><nn>.mat`` (a 7-sensor x 6-value matrix ``data`` at 250 Hz and ``fs``), three
    speakers, no phone labels, no '_' in the names; x anterior, y lateral (left), z up. Returns the paths."""
    import scipy.io

    from engine.talker.multispeaker import generate_recordings

    folder.mkdir(parents=True, exist_ok=True)
    count, paths = {}, []
    for r in generate_recordings(n_speakers=3, n_utterances=n_utterances, duration_s=duration_s, seed=seed):
        count[r.speaker] = count.get(r.speaker, 0) + 1
        p = folder / f"{LAB_CODES[r.speaker]}{count[r.speaker]:02d}.mat"
        scipy.io.savemat(p, {"data": r.matrix, "fs": np.array([[r.rate]])}, do_compression=compress)
        paths.append(p)
    return paths


@pytest.fixture(scope="session")
def lab_folder(tmp_path_factory):
    """(folder, paths): nine recordings of three speakers, ABCFIA01.mat ... XYMNE03.mat."""
    d = tmp_path_factory.mktemp("lab") / "matfiles"
    return d, write_lab_folder(d)


@pytest.fixture(scope="session")
def tiny_manifold_file(small_corpus, tmp_path_factory):
    """A manifold of the talker's first three utterances (20 states), its corpus.npz beside it."""
    from engine.manifold.model import Manifold

    tiny = small_corpus.subset([u.id for u in small_corpus.utterances[:3]])
    d = tmp_path_factory.mktemp("tiny")
    tiny.save(d / "corpus.npz")
    return Manifold(n_states=20).fit(tiny).save(d / "m.npz")


def run_cli(argv) -> tuple[int, str, str]:
    """``lipspace ARGV`` in this process: ``(exit code, stdout, stderr)``."""
    import contextlib
    import io

    from app.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture(scope="session")
def cli():
    """:func:`run_cli`: run a ``lipspace`` command, capturing its exit code and output."""
    return run_cli


class RunningBuild:
    """``lipspace build ARGV`` in a child process, watched until it says it is fitting.

    Its stdout is read line by line on a thread (unbuffered: ``PYTHONUNBUFFERED``), its stderr
    goes to a file; :meth:`wait_until_fitting` returns once the build has printed its plan
    (``lipspace build: N frames: embedding ...``), the line it prints when the corpus is
    loaded and the fit starts. The timeout only bounds a failure, it is never the signal.
    """

    def __init__(self, argv, folder):
        import os
        import subprocess
        import sys
        import threading

        self.stderr_path = folder / "build-stderr.txt"
        self._err = open(self.stderr_path, "w", encoding="utf-8")  # closed in finish()
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.proc = subprocess.Popen([sys.executable, "-m", "app.cli", "build", *map(str, argv)],
                                     stdout=subprocess.PIPE, stderr=self._err, text=True, env=env)
        self.lines: list[str] = []
        self._fitting = threading.Event()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in self.proc.stdout:
            self.lines.append(line)
            if line.startswith("lipspace build: ") and " frames: embedding " in line:
                self._fitting.set()
        self._fitting.set()  # the output ended: wait_until_fitting says whether it was the plan

    def wait_until_fitting(self, timeout_s: float = 600.0) -> None:
        """Block until the build prints its plan; fail (with its output) if it ends or times out first."""
        assert self._fitting.wait(timeout_s), f"no build plan within {timeout_s:g} s: {self.lines}"
        assert self.proc.poll() is None, f"the build ended before fitting: {self.lines} {self.stderr()[-2000:]}"

    def finish(self, timeout_s: float = 120.0) -> str:
        """Wait for the exit; its stderr."""
        try:
            self.proc.wait(timeout_s)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()
            self._reader.join(timeout_s)
            self.proc.stdout.close()
            self._err.close()
        return self.stderr()

    def stderr(self) -> str:
        return self.stderr_path.read_text(encoding="utf-8", errors="replace")


@pytest.fixture
def running_build(tmp_path_factory):
    """``running_build(argv) -> RunningBuild``; any build still running at the test's end is killed."""
    builds = []

    def start(argv):
        b = RunningBuild(argv, tmp_path_factory.mktemp("build-log"))
        builds.append(b)
        return b

    yield start
    for b in builds:
        if b.proc.poll() is None:
            b.proc.kill()
        b.finish()
