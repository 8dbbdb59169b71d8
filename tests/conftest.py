"""Shared fixtures: the small synthetic corpus and its manifold, built once per session."""
from __future__ import annotations

import itertools
import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"


def pytest_configure(config):
    # never write into the user's real cache from tests
    if "LIPSPACE_CACHE_DIR" not in os.environ:
        import tempfile

        os.environ["LIPSPACE_CACHE_DIR"] = tempfile.mkdtemp(prefix="lipspace-test-cache-")
    # nor autosave into the user's real state dir (app.files.autosave)
    if "LIPSPACE_STATE_DIR" not in os.environ:
        import tempfile

        os.environ["LIPSPACE_STATE_DIR"] = tempfile.mkdtemp(prefix="lipspace-test-state-")


@pytest.fixture(scope="session")
def small_corpus():
    from engine.talker.synthetic import load_synthetic

    return load_synthetic(preset="small")


@pytest.fixture(scope="session")
def small_manifold(small_corpus):
    from engine.manifold.model import Manifold

    return Manifold().fit(small_corpus)


@pytest.fixture(scope="session")
def shared_data():
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real sample data not found at {SHARED_DATA} (../shared/data beside the project)")
    return SHARED_DATA


@pytest.fixture(scope="session")
def mocha_manifold(shared_data):
    """The manifold of the MOCHA sample (fsew0_001: lip sensors, a .lab alignment, audio) at 60 Hz."""
    import warnings

    from engine.io import read_corpus, resample
    from engine.manifold.model import Manifold

    d = shared_data / "mocha-fsew0"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a 2-s, 116-frame corpus: the data warnings are expected
        corpus = resample(read_corpus(d / "fsew0_001.ema", alignment=d / "fsew0_001.lab"), 60.0)
        return Manifold().fit(corpus)


@pytest.fixture(scope="session")
def praat(tmp_path_factory):
    """``praat(script, *args) -> stdout``: run a Praat script with the real program (``praat --run``).

    Skips the test where Praat is not installed (``.ci/run`` installs Debian's ``praat``).
    """
    exe = shutil.which("praat")
    if exe is None:
        pytest.skip("Praat is not installed (apt-get install praat; .ci/run does)")
    folder, count = tmp_path_factory.mktemp("praat"), itertools.count()

    def run(script: str, *args, timeout: float = 300) -> str:
        path = folder / f"script{next(count)}.praat"
        path.write_text(script, encoding="utf-8")
        r = subprocess.run([exe, "--run", str(path), *map(str, args)], capture_output=True, text=True, timeout=timeout)
        assert r.returncode == 0, f"praat --run {path.name}: {r.stderr}"
        return r.stdout

    return run


@pytest.fixture(scope="session")
def dask_cluster():
    """One two-worker in-process Dask LocalCluster for every Dask test (starting one costs seconds).

    Threads, not processes (``processes=False``); the scheduler's HTTP server on a free port.
    Tests connect with ``Client(dask_cluster)`` or pass ``dask_cluster.scheduler_address`` to a command.
    """
    pytest.importorskip("distributed")
    from distributed import LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=":0")
    yield cluster
    cluster.close()


@pytest.fixture(scope="session")
def conditions():
    """``(ConditionCorpus, Manifold)``: three conditions of the small synthetic talker, each of 10 sentences said
    twice (paired by text) -- ``a`` as spoken, ``b`` with wider bilabial releases, ``c`` with slower closing
    (:mod:`engine.talker.conditions`) -- and the one manifold fitted on all of them."""
    from engine.manifold.model import Manifold
    from engine.talker.conditions import condition_corpus

    cc = condition_corpus(conditions={"a": "none", "b": "bilabial_release", "c": "slow_closing"}, n_texts=10,
                          repetitions=2, preset="small", seed=0)
    return cc, Manifold().fit(cc.corpus)


#: the lab folder's speakers (code, sex) and emotions, as a lab names its files (XYZFNE01.pos ...)
LAB_SPEAKERS = (("XYZ", "F"), ("ABCD", "M"), ("EF", "F"))
LAB_EMOTIONS = ("NE", "AN", "SA")


@pytest.fixture(scope="session")
def ag501_lab(tmp_path_factory):
    """A lab's AG501 folder (engine.talker.lab_files): 3 speakers x 3 emotions x 2 texts as ``<spk><sex><emo><nn>.pos``
    sweeps with real headers and rms columns, speaker XYZ's upper-lip coil bad, the lab's layout file, a metadata
    table (``;``, BOM) missing one recording and naming one that is not there, and a notes file.

    Returns ``(folder, sweeps, pos paths)``."""
    from engine.talker.lab_files import BadSensor, lab_sweeps, write_ag501_folder

    folder = tmp_path_factory.mktemp("ag501") / "session1"
    sweeps = lab_sweeps(speakers=LAB_SPEAKERS, emotions=LAB_EMOTIONS, texts=2, duration_s=(0.8, 1.0),
                        bad=BadSensor("XYZ"), seed=11)
    paths = write_ag501_folder(folder, sweeps, leave_out=("EFFSA02",), extra=("QRSMNE01",))
    return folder, sweeps, paths


def haskins_file(path, *, seconds=2.0, words=("sp", "BOB", "MEETS", "MUM", "sp"), seed=0, audio=True):
    """An MVIEW ``.mat`` made as the Haskins IEEE files are: one struct array named after the file, entry 1
    ``AUDIO`` (44.1 kHz, a voiced sound with syllable-rate loudness) holding ``SENTENCE``, ``WORDS`` and
    ``PHONES`` (``LABEL`` and ``OFFS`` [start end] s, ARPAbet, ``sp`` pauses), then the sensors
    TR TB TT UL LL ML JAW JAWL, each ``SIGNAL`` (n, 6) at 100 Hz: x anterior, y lateral, z vertical in mm."""
    import numpy as np
    import scipy.io

    rng = np.random.default_rng(seed)
    rate, sr = 100.0, 44100.0
    n = int(seconds * rate)
    t = np.arange(n) / rate
    opening = 6 + 5 * np.sin(2 * np.pi * 3.7 * t) + 0.2 * rng.standard_normal(n)
    edges = np.linspace(0.0, seconds, len(words) + 1)
    pron = {"BOB": ("B", "AA1", "B"), "MEETS": ("M", "IY1", "T", "S"), "MUM": ("M", "AH1", "M")}
    word_rows, phone_rows = [], []
    for w, a, b in zip(words, edges[:-1], edges[1:]):
        word_rows.append((w, np.array([[a, b]])))
        ph = pron.get(w, ("sp",))
        cuts = np.linspace(a, b, len(ph) + 1)
        phone_rows += [(p, np.array([[c0, c1]])) for p, c0, c1 in zip(ph, cuts[:-1], cuts[1:])]

    def struct(rows):
        s = np.zeros((1, len(rows)), dtype=[("LABEL", "O"), ("OFFS", "O")])
        for k, (lab, offs) in enumerate(rows):
            s[0, k] = (lab, offs)
        return s

    dt = [("NAME", "O"), ("SRATE", "O"), ("SIGNAL", "O"), ("SOURCE", "O"), ("SENTENCE", "O"), ("WORDS", "O"),
          ("PHONES", "O"), ("LABELS", "O")]
    names = ("TR", "TB", "TT", "UL", "LL", "ML", "JAW", "JAWL")
    s = np.zeros((1, (1 if audio else 0) + len(names)), dtype=dt)
    k0 = 0
    sentence = " ".join(w for w in words if w != "sp").capitalize() + "."
    if audio:
        ts = np.arange(int(seconds * sr)) / sr
        snd = np.sin(2 * np.pi * 120 * ts) * (0.5 + 0.5 * np.sin(2 * np.pi * 3.7 * ts)) * 0.3
        s[0, 0] = ("AUDIO", sr, snd.astype(np.float32)[:, None], "", sentence, struct(word_rows), struct(phone_rows),
                   np.zeros((0, 0)))
        k0 = 1
    for k, name in enumerate(names):
        sig = 0.1 * rng.standard_normal((n, 6))
        sig[:, 0] += 60 + 10 * (k % 3)
        sig[:, 2] += {"UL": opening / 2, "LL": -opening / 2, "JAW": -opening, "JAWL": -opening}.get(name, 0.0) + k
        first = k == 0 and not audio
        s[0, k0 + k] = (name, rate, sig.astype(np.float32), "", sentence if first else "",
                        struct(word_rows) if first else np.zeros((0, 0)),
                        struct(phone_rows) if first else np.zeros((0, 0)), np.zeros((0, 0)))
    scipy.io.savemat(path, {path.stem: s})
    return path


@pytest.fixture(scope="session")
def make_haskins_file():
    """:func:`haskins_file`: ``make_haskins_file(tmp_path / "F01_B01_S01_R01_N.mat", seconds=2.0)``."""
    return haskins_file


# --------------------------------------------------------------------------- no window outlives its test
def _visible_top_levels() -> dict[int, str]:
    """``{id: description}`` of the visible Qt top-level widgets (none when Qt was never imported)."""
    import sys

    if "PySide6.QtWidgets" not in sys.modules:
        return {}
    from PySide6.QtWidgets import QApplication

    if QApplication.instance() is None:
        return {}
    return {id(w): f"{type(w).__name__} {w.windowTitle()!r}" for w in QApplication.topLevelWidgets()
            if w.isVisible()}


def _open_plotters() -> dict[str, str]:
    """``{id: description}`` of the pyvista plotters not closed (none when pyvista was never imported)."""
    import sys

    if "pyvista" not in sys.modules:
        return {}
    from pyvista.plotting.plotter import _ALL_PLOTTERS

    return {k: type(p).__name__ for k, p in _ALL_PLOTTERS.items() if not getattr(p, "_closed", False)}


def _settle_qt() -> None:
    """Run Qt's pending events and deferred deletions, so a window closed at the test's end is gone."""
    import sys

    if "PySide6.QtWidgets" not in sys.modules:
        return
    from PySide6.QtCore import QCoreApplication, QEvent
    from PySide6.QtWidgets import QApplication

    if QApplication.instance() is not None:
        QApplication.processEvents()
        QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
        QApplication.processEvents()


@pytest.fixture(autouse=True)
def no_window_left_open(request):
    """Fail a test that leaves a visible Qt top-level window or an open VTK plotter behind (after
    MNE's ``brain_gc`` and napari's ``make_napari_viewer``): each one left open kept its render
    window, and a later test's picking, screenshots or focus met it.

    Windows and plotters that module- or session-scoped fixtures made before the test (a shared
    explorer window) are theirs to close and are not counted. What is found is closed, so one
    leak fails one test.
    """
    windows, plotters = _visible_top_levels(), _open_plotters()
    yield
    _settle_qt()
    new_windows = {k: v for k, v in _visible_top_levels().items() if k not in windows}
    new_plotters = {k: v for k, v in _open_plotters().items() if k not in plotters}
    if not new_windows and not new_plotters:
        return
    if new_windows:
        from PySide6.QtWidgets import QApplication

        for w in QApplication.topLevelWidgets():
            if id(w) in new_windows:
                w.close()
    if new_plotters:
        from pyvista.plotting.plotter import _ALL_PLOTTERS

        for k in new_plotters:
            p = _ALL_PLOTTERS.get(k)
            if p is not None:
                p.close()
    _settle_qt()
    left = sorted(new_windows.values()) + [f"pyvista {v}" for v in sorted(new_plotters.values())]
    pytest.fail(f"{request.node.nodeid} left open: {', '.join(left)}; close them in the test "
                "(qtbot.addWidget, a fixture's teardown, plotter.close())", pytrace=False)
