"""Regenerate the explorer screenshots in this folder (run under a virtual X server).

    xvfb-run -a -s "-screen 0 1920x1200x24" .venv/bin/python docs/screenshots/make_screenshots.py \
        MANIFOLD.npz default docs/screenshots

MANIFOLD.npz: e.g. the cached synthetic-talker manifold that 'lipspace explore' writes
(<cache>/manifolds/synthetic-default-*.npz) or one from 'lipspace build -o m.npz'.
"""
import sys
import time

import numpy as np
from pathlib import Path
from PySide6 import QtWidgets
app = QtWidgets.QApplication([])
from engine.manifold.model import Manifold
from app.main_window import MainWindow
path, preset, out = sys.argv[1], sys.argv[2], Path(sys.argv[3])
out.mkdir(parents=True, exist_ok=True)
m = Manifold.load(path)
w = MainWindow(m, source={"path": None, "preset": preset})
w.resize(1600, 1000); w.show()
def pump(n=10):
    for _ in range(n):
        app.processEvents(); time.sleep(0.02)
pump()
s = w.state
# 1. hemisphere: a frame on the opening side, mid-utterance
u = m.corpus_.utterances[3]
s.set_utterance(u.id)
t = m.tangent_
cam = np.array(w.manifold_view.plotter.camera.position)
Y3 = m.Fy_[:, :3]
cands = np.flatnonzero((t.classes_ == 0))
i = int(cands[np.argmin(np.linalg.norm(Y3[cands] - cam, axis=1))])
s.select_frame(i)
d = m.states_.future(s.state)
C = m.states_.centroids_[:, :3]
far = np.flatnonzero(np.isfinite(d) & (d >= 5))
s.set_target(int(far[np.argmin(np.linalg.norm(C[far] - cam, axis=1))]))
pump()
w.manifold_view.renderer.flush(); w.lip_view.renderer.flush(); pump()
w.grab().save(str(out / "main_hemisphere.png"))
# 2. clusters: bilabials
s.set_utterance(None); s.clear_selection(); s.set_color_mode("density")
labs = [r["phone"] for r in s.cluster_rows()]
want = [p for p in ("b", "p", "m") if p in labs]
s.set_visible_phones(want)
w.manifold_view.points_box.setChecked(False)
w.docks["clusters"].raise_()
tbl = w.clusters.table
rows = [i for i in range(tbl.rowCount()) if tbl.item(i, 0).text() in want]
tbl.scrollToItem(tbl.item(max(rows), 0))
pump(); w.manifold_view.renderer.flush(); pump()
w.grab().save(str(out / "clusters_ellipsoids.png"))
# 3. synthesis from an utterance, red trajectory + playback side by side
s.set_visible_phones(())
w.manifold_view.points_box.setChecked(True)
ed = w.editor
ed.set_source("utterance"); ed.utt_box.setCurrentIndex(5); ed.load(); ed.set_method("manifold")
r = ed.synthesize(); r.wait()
pump()
s.set_color_mode("density")
w.manifold_view.points_box.setChecked(False)
s.set_playback(len(s.original) // 2)
pump(); w.manifold_view.renderer.flush(); w.lip_view.renderer.flush(); pump()
w.grab().save(str(out / "synthesis_editor.png"))
print(ed.readout.text())
# 4. scree and component 1 as a deformation
s.set_playing(False); s.set_trajectories(original=None, synthetic=None)
w.manifold_view.points_box.setChecked(True)
w.docks["scree"].raise_()
w.scree.spin.setValue(1); w.scree.show_box.setChecked(True)
pump(); w.manifold_view.renderer.flush(); w.lip_view.renderer.flush(); pump()
w.grab().save(str(out / "scree_components.png"))
w.close()
