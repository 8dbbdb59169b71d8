import sys

import numpy as np
import pyvista as pv

sys.path.insert(0, '/work/main')
from app.scene.lips import add_lips
from engine.talker.synthetic import SyntheticTalker

c = SyntheticTalker(preset="small", resolution="default", duration=120).generate()
mids, labels, *_ = c.phone_table()
ap = c.latent["aperture"]
pl = pv.Plotter(off_screen=True, shape=(2, 4), window_size=(1600, 760), border=False)
picks = [("sil", "rest (pause)"), ("m", "/m/"), ("f", "/f/"), ("uw", "/uw/ (rounded)"), ("iy", "/iy/ (spread)"),
         ("aa", "/aa/ (open)"), ("sh", "/sh/ (protruded)"), ("th", "/th/")]
for i, (p, title) in enumerate(picks):
    idx = mids[labels == p]
    k = idx[np.argsort(ap[idx])[len(idx) // 2]]
    pl.subplot(i // 4, i % 4)
    add_lips(pl, c.frames[k].reshape(-1, 3), c.faces, color=(0.78, 0.32, 0.34), names=c.point_names)
    pl.add_text(title, font_size=11, color="black")
    pl.view_xy()
    pl.camera.azimuth = 25 if i % 2 else 0
    pl.camera.elevation = 8
    pl.reset_camera()
    pl.camera.zoom(1.25)
pl.set_background("white")
pl.screenshot(sys.argv[1])
