"""Regenerate the explorer screenshots in this folder (run under a virtual X server).

    xvfb-run -a -s "-screen 0 1920x1200x24" .venv/bin/python docs/screenshots/make_screenshots.py \
        MANIFOLD.npz default docs/screenshots [HASKINS.mat]

MANIFOLD.npz: e.g. the cached synthetic-talker manifold that 'lipspace explore' writes
(<cache>/manifolds/synthetic-default-*.npz) or one from 'lipspace build -o m.npz'. HASKINS.mat:
a Haskins IEEE file (e.g. ../shared/data/haskins-ieee/F01_B01_S01_R01_N.mat), opened as File › Open
opens it, for the timeline with its word tier, waveform and spectrogram (left out when not given).

Each picture is taken at 1600 x 1000 (``<name>.png``) and at a laptop's 1280 x 720
(``<name>_1280x720.png``).
"""
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PySide6 import QtWidgets

app = QtWidgets.QApplication([])
from app.main_window import MainWindow  # noqa: E402
from engine.manifold.model import Manifold  # noqa: E402

path, preset, out = sys.argv[1], sys.argv[2], Path(sys.argv[3])
haskins = sys.argv[4] if len(sys.argv) > 4 else None
out.mkdir(parents=True, exist_ok=True)
m = Manifold.load(path)
SIZES = ((1600, 1000, ""), (1280, 720, "_1280x720"))


def pump(n=10):
    for _ in range(n):
        app.processEvents()
        time.sleep(0.02)


def save(w, name, suffix):
    pump()
    w.manifold_view.renderer.flush()
    w.lip_view.renderer.flush()
    pump()
    w.grab().save(str(out / f"{name}{suffix}.png"))


def wait(runner, timeout=600):
    t0 = time.perf_counter()
    while runner.state == "running" and time.perf_counter() - t0 < timeout:
        pump(2)


for W, H, suffix in SIZES:
    # the default layout, not the one this machine's (or the last size's) window left
    os.environ["LIPSPACE_CONFIG_DIR"] = tempfile.mkdtemp(prefix="lipspace-shots-")
    w = MainWindow(m, source={"path": None, "preset": preset})
    w.resize(W, H)
    w.show()
    w.docks["clusters"].raise_()  # not the tab the last window left raised
    pump()
    s, ed = w.state, w.editor
    # 1. the future hemisphere of a frame on the opening side, a path to a far state, an utterance: the legends
    u = m.corpus_.utterances[3]
    s.set_utterance(u.id)
    cam = np.array(w.manifold_view.plotter.camera.position)
    Y3 = m.Fy_[:, :3]
    cands = np.flatnonzero(m.tangent_.classes_ == 0)
    i = int(cands[np.argmin(np.linalg.norm(Y3[cands] - cam, axis=1))])
    s.select_frame(i)
    d = m.states_.future(s.state)
    C = m.states_.centroids_[:, :3]
    far = np.flatnonzero(np.isfinite(d) & (d >= 5))
    s.set_target(int(far[np.argmin(np.linalg.norm(C[far] - cam, axis=1))]))
    save(w, "main_hemisphere", suffix)
    # 2. /p b m/: ticked in the clusters table, framed (F), coloured by phone with the filter: one colour each
    s.set_utterance(None)
    s.clear_selection()
    labs = [r["phone"] for r in s.cluster_rows()]
    want = [p for p in ("b", "p", "m") if p in labs]
    s.set_color_mode("phone")
    s.set_phone_filter(want)
    s.set_visible_phones(want)
    s.set_ellipsoid_opacity(0.35)
    w.docks["clusters"].raise_()
    tbl = w.clusters.table
    rows = [k for k in range(tbl.rowCount()) if tbl.item(k, 0).text() in want]
    tbl.scrollToItem(tbl.item(max(rows), 0))
    pump()
    w.frame_action.trigger()
    save(w, "clusters_ellipsoids", suffix)
    # 3. typed text synthesised (spoken when espeak-ng is installed): red trajectory, word tier, a selection
    s.reset_settings()
    ed.set_method("manifold")
    ed.set_text("bob meets mum", source="text")
    wait(ed.synthesize())
    pump()
    s.set_playback(len(s.synthetic) // 2)
    w.reset_cameras()
    w.frame_action.trigger()  # nothing selected: the trajectory framed
    n = ed.targets.n_frames
    ed.set_time_selection((0.3 * n, 0.6 * n))
    save(w, "synthesis_editor", suffix)
    # 4. a Haskins file opened directly: its word tier, waveform and spectrogram under the phones
    if haskins:
        wait(w.open_source(haskins))
        pump(20)
        ed.set_source("utterance")
        ed.load()
        t0 = time.perf_counter()
        while ed.sound.shown_at is None and time.perf_counter() - t0 < 60:
            pump(2)
        n = ed.targets.n_frames
        ed.set_cursor_frame(int(0.45 * n))
        ed.set_time_selection((0.3 * n, 0.42 * n))
        save(w, "timeline_praat", suffix)
        w.set_manifold(m, source={"path": None, "preset": preset})
    # 5. the scree and component 1 as a deformation
    s.set_playing(False)
    s.set_trajectories(original=None, synthetic=None)
    w.docks["scree"].raise_()
    w.scree.spin.setValue(1)
    w.scree.show_box.setChecked(True)
    save(w, "scree_components", suffix)
    print(suffix or "1600x1000", ed.readout.text())
    w.close()
