"""Benchmark: File > Export figure of the manifold view (SVG, PDF vector; PNG at 300 dpi) and the hover look-up.

Usage: python benchmarks/bench_view_export.py [--repeats 3] [--preset default]

Opens the explorer's manifold view on the default synthetic talker (28,800 frames) under
an X server (re-runs itself under ``xvfb-run`` without one), selects a frame (hemisphere
colours, marker, local frame) and a path target, then times in one process (warm):

* ``save_plotter_vector`` to .svg and .pdf (the scene redrawn as vector paths) and the
  written size;
* ``save_plotter_image`` at 300 dpi;
* the hover look-up (project every point through the camera + nearest point on screen),
  with the projection cache cleared each time (a moved camera) and kept (pointer moves).

Prints min / median of the repeats, peak RSS and the BLAS kernel.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _gui_bench as gb  # noqa: E402
from _harness import Harness  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--preset", default="default")
    Harness.add_arguments(ap)
    args = ap.parse_args()
    gb.ensure_display()
    bench = Harness("bench_view_export", args)
    gb.header("manifold view: vector / PNG export and hover look-up (warm, one process)")
    import numpy as np
    from PySide6 import QtWidgets

    m, _src = gb.default_manifold(args.preset)
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    from app.figures.export import save_plotter_image, save_plotter_vector
    from app.models.state import AppState
    from app.scene import pick_display_point
    from app.views.manifold_view import ManifoldView

    state = AppState(m)
    view = ManifoldView(state)
    view.resize(1000, 700)
    view.show()
    gb.settle(app, 0.5)
    labels = m.states_.labels_
    state.select_frame(int(np.argmin(np.linalg.norm(m.Fy_[:, :3] - m.Fy_[:, :3].mean(0), axis=1))))
    state.set_target(int(labels[len(labels) // 2]))
    view.renderer.flush(sync=True)
    size = view.plotter.window_size
    print(f"   {m.Fy_.shape[0]} frames; view {size[0]}x{size[1]} px; OpenGL {gb.gl_renderer(view.plotter)}")
    out = Path(tempfile.mkdtemp(prefix="bench_view_export_"))
    for suffix in (".svg", ".pdf"):
        times = []
        for k in range(args.repeats):
            t = time.perf_counter()
            p = save_plotter_vector(view.plotter, out / f"view{k}{suffix}")
            times.append(time.perf_counter() - t)
        print(f"{suffix} vector export: {gb.stats(times, 's', 1.0)}; {p.stat().st_size / 1e6:.1f} MB")
        bench.figure(f"{suffix} vector export", times, first_is_separate=True, headline=suffix == ".svg", show=False,
                     file_mb=p.stat().st_size / 1e6)
    times = []
    for k in range(args.repeats):
        t = time.perf_counter()
        p = save_plotter_image(view.plotter, out / f"view{k}.png", dpi=300)
        times.append(time.perf_counter() - t)
    print(f"PNG at 300 dpi: {gb.stats(times, 's', 1.0)}; {p.stat().st_size / 1e6:.1f} MB")
    bench.figure("PNG at 300 dpi", times, first_is_separate=True, headline=True, show=False)
    x, y = pick_display_point(view.plotter, m.Fy_[state.frame, :3])
    cold, warm = [], []
    for _ in range(20):
        view._hover_cache = None
        t = time.perf_counter()
        view.hover_frame((x, y))
        cold.append(time.perf_counter() - t)
        t = time.perf_counter()
        view.hover_frame((x + 3, y + 2))
        warm.append(time.perf_counter() - t)
    print(f"hover look-up, camera moved (projection of every point): {gb.stats(cold)}")
    print(f"hover look-up, camera still (projection cached):         {gb.stats(warm)}")
    bench.figure("hover look-up, camera moved", cold, show=False)
    bench.figure("hover look-up, camera still", warm, show=False)
    for f in out.iterdir():
        f.unlink()
    out.rmdir()
    view.close_view()
    bench.finish()


if __name__ == "__main__":
    main()
