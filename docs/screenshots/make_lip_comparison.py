"""Compare the synthetic talker's lip surface with a FaceMesh lip surface from a video import.

    xvfb-run -a .venv/bin/python docs/screenshots/make_lip_comparison.py docs/screenshots

Needs the [video] extra (mediapipe, scikit-image). A still video of scikit-image's
astronaut photo is imported as a real user's video would be (FaceMesh lips, head pose
removed, mm from the 63 mm inter-ocular assumption); the default talker's frame nearest
to rest (smallest aperture change) is taken from its corpus. Both are measured the same
way (mouth width between the corners, upper and lower lip height at the midline) and
drawn side by side from the front with the lip view's shading (lip_comparison.png).
"""
import sys
import tempfile
from pathlib import Path

import numpy as np
import pyvista as pv
from skimage import data as skdata

from app.scene.lips import add_lips
from engine.io.video.clips import read_video
from engine.io.video.facemesh import LIP_NAMES, LIP_RINGS
from engine.io.video.synth import moving_image_frames, write_video
from engine.talker.lipmodel import vermilion_weight
from engine.talker.synthetic import load_synthetic


def lip_heights(P, upper, lower):
    """Mouth width (x range) and the upper and lower lips' heights (y range) near the midline."""
    width = P[:, 0].max() - P[:, 0].min()
    mid = np.abs(P[:, 0] - np.median(P[:, 0])) < 0.08 * width
    hu = np.ptp(P[upper & mid, 1])
    hl = np.ptp(P[lower & mid, 1])
    return width, hu, hl


def facemesh_lips(tmp):
    img = np.ascontiguousarray(skdata.astronaut()[0:256, 96:352])
    path = Path(tmp) / "still.mp4"
    write_video(path, moving_image_frames(img, np.tile([0.0, 1.0, 0.0, 0.0], (10, 1))), 30.0)
    c = read_video(path, alignment=False, audio_dir=tmp)
    P = c.points(0) if callable(getattr(c, "points", None)) else c.frames[0].reshape(-1, 3)
    P = np.asarray(P, float).reshape(-1, 3)
    pos = np.array([int(n.split("_")[-1]) for n in LIP_NAMES])
    k = np.array([LIP_RINGS[n.rsplit("_", 1)[0]].index(i) for n, i in zip(LIP_NAMES, pos)])
    upper, lower = (k >= 11), (k >= 1) & (k <= 9)
    return P, np.asarray(c.faces), upper, lower


def talker_lips():
    c = load_synthetic(preset="default")
    F = c.frames.reshape(c.n_frames, -1, 3)
    w = vermilion_weight(c.point_names) > 0.5
    names = np.array(c.point_names)
    upper = np.array([n[0] == "U" for n in names]) & w
    lower = np.array([n[0] == "L" for n in names]) & w
    # rest: the frame whose vermilion is least spread vertically at the midline (lips together)
    gaps = [lip_heights(f[w], upper[w], lower[w]) for f in F[:: max(1, len(F) // 2000)]]
    i = int(np.argmin([g[1] + g[2] for g in gaps])) * max(1, len(F) // 2000)
    return F[i], np.asarray(c.faces), upper, lower, c.point_names


def main(out):
    out = Path(out)
    with tempfile.TemporaryDirectory() as tmp:
        Pv, fv, uv, lv = facemesh_lips(tmp)
    Pt, ft, ut, lt, names = talker_lips()
    rows = []
    for label, P, u, lo in (("video (FaceMesh)", Pv, uv, lv), ("synthetic talker", Pt, ut, lt)):
        W, hu, hl = lip_heights(P[u | lo], u[u | lo], lo[u | lo])
        rows.append((label, W, hu, hl))
        print(f"{label:18s} mouth width {W:5.1f} mm, upper lip {hu:4.1f} mm, lower lip {hl:4.1f} mm, "
              f"upper/lower {hu / hl:4.2f}, width/(upper+lower) {W / (hu + hl):4.2f}")
    p = pv.Plotter(off_screen=True, window_size=(1000, 420), shape=(1, 2))
    for j, (P, F, nm, title) in enumerate(((Pv, fv, None, "video import (FaceMesh, astronaut photo)"),
                                           (Pt, ft, names, "synthetic talker (default preset)"))):
        p.subplot(0, j)
        add_lips(p, P - P.mean(0), F, names=nm)
        p.add_text(title, font_size=9)
        p.view_xy()
        p.camera.zoom(1.3)
    p.screenshot(str(out / "lip_comparison.png"))
    p.close()
    return rows


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/screenshots")
