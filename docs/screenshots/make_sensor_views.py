"""Screenshots of articulograph recordings in the explorer: sensors drawn and labelled as sensors.

    xvfb-run -a -s "-screen 0 1920x1200x24" .venv/bin/python docs/screenshots/make_sensor_views.py \
        docs/screenshots MOCHA.ema HASKINS.mat

MOCHA.ema: a MOCHA-TIMIT midsagittal file (e.g. fsew0_001.ema, its .lab beside it): the lip view is a
profile (UL, LL, LI) with the face direction. HASKINS.mat: a Haskins IEEE file (UL, LL, ML, JAW, JAWL
and the tongue): sensors joined by straight lines, every label placed, the aperture a segment with its
value in mm. Each recording's manifold is fitted here as ``lipspace build`` fits it; each picture is
taken at 1600 x 1000 (``sensors_<name>.png``) and 1280 x 720 (``sensors_<name>_1280x720.png``).
"""
import sys
import time
import warnings
from pathlib import Path

from PySide6 import QtWidgets

app = QtWidgets.QApplication([])
from app.files.source_loading import read_recording  # noqa: E402
from app.main_window import MainWindow  # noqa: E402
from engine.manifold.model import Manifold  # noqa: E402

out = Path(sys.argv[1])
out.mkdir(parents=True, exist_ok=True)
SIZES = ((1600, 1000, ""), (1280, 720, "_1280x720"))


def pump(n=10):
    for _ in range(n):
        app.processEvents()
        time.sleep(0.02)


for name, path in zip(("mocha", "haskins"), sys.argv[2:4]):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the import notes (an alignment past the data) are the window's to show
        m = Manifold().fit(read_recording(path))
    u = m.corpus_.utterances[0]
    for W, H, suffix in SIZES:
        w = MainWindow(m, source={"path": str(path), "preset": None})
        w.resize(W, H)
        w.show()
        pump()
        w.state.set_utterance(u.id)
        w.state.select_frame(u.start + u.n_frames // 3)  # a third into the utterance: lips apart
        pump()
        w.manifold_view.renderer.flush()
        w.lip_view.renderer.flush()
        pump()
        w.grab().save(str(out / f"sensors_{name}{suffix}.png"))
        print("wrote", out / f"sensors_{name}{suffix}.png")
        w.close()
