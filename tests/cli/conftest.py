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
