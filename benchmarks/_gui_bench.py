"""Shared set-up of the GUI benchmarks (bench_gui_click.py, bench_gui_playback.py, bench_gui_startup.py).

They drive the real explorer window (``app.main_window.MainWindow``) under an X server.
Without a DISPLAY a script re-runs itself under ``xvfb-run -a -s "-screen 0 1600x1200x24"``
(software OpenGL: Mesa llvmpipe). The default synthetic talker's manifold (28,800 frames)
is built once into the cache (``$LIPSPACE_CACHE_DIR`` or the user cache dir) if missing.
"""
from __future__ import annotations

import os
import platform
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

XVFB_ARGS = ["-a", "-s", "-screen 0 1600x1200x24"]
WINDOW_SIZE = (1400, 900)


def ensure_display() -> None:
    """Re-execute this script under xvfb-run when there is no display (exits with its code)."""
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return
    exe = shutil.which("xvfb-run")
    if exe is None:
        sys.exit("no DISPLAY and no xvfb-run: install xvfb (apt-get install xvfb) or run under an X server")
    sys.exit(subprocess.call([exe, *XVFB_ARGS, sys.executable, *sys.argv]))


def blas_kernel() -> str:
    from _common import blas_kernel as kernel

    return kernel()


def peak_rss_mb() -> float:
    """Peak resident memory of this process (MiB): :func:`_common.peak_rss_mb`."""
    from _common import peak_rss_mb as peak

    return peak()


def gl_renderer(plotter) -> str:
    """The OpenGL renderer string of a plotter's render window (e.g. 'llvmpipe (LLVM 15.0.6, 256 bits)')."""
    try:
        caps = plotter.render_window.ReportCapabilities()
    except Exception:  # noqa: BLE001 - only a label
        return "unknown"
    for line in caps.splitlines():
        if "renderer string" in line.lower():
            return line.split(":", 1)[1].strip()
    return "unknown"


def header(title: str) -> None:
    import numpy as np

    print(f"== {title}")
    print(f"   python {platform.python_version()}, numpy {np.__version__}, BLAS {blas_kernel()}")
    print(f"   {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at start, DISPLAY={os.environ.get('DISPLAY')}")


def default_manifold(preset: str = "default"):
    """The synthetic talker's manifold from the explorer's cache (built and cached when missing)."""
    try:
        from app.source_loading import cached_manifold_path, load_source
    except ImportError:  # trees before app.source_loading (bench_gui_playback.py --tree)
        from app.cli.explore import cached_manifold_path, load_source

    path = cached_manifold_path(preset)
    how = "loaded from" if path.exists() else "built; cache"  # asked before loading writes the cache
    t = time.perf_counter()
    m, src = load_source(None, preset)
    print(f"   manifold: synthetic talker '{preset}', {m.Fy_.shape[0]} frames, {how} {path} "
          f"({time.perf_counter() - t:.1f} s)")
    return m, src


def open_window(manifold, source):
    """The explorer's main window on ``manifold``, shown and idle (returns (app, window))."""
    from PySide6 import QtWidgets

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    from app.main_window import MainWindow

    win = MainWindow(manifold, source=source)
    win.resize(*WINDOW_SIZE)
    win.show()
    settle(app, 1.0)
    return app, win


def settle(app, seconds: float) -> None:
    """Run the event loop for ``seconds``."""
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        app.processEvents()
        time.sleep(0.002)


class RenderLog:
    """Times of VTK renders (render window EndEvent) and of frames reaching the screen (frameSwapped)."""

    def __init__(self, plotter):
        self.starts: list[float] = []
        self.renders: list[float] = []
        self.swaps: list[float] = []
        plotter.render_window.AddObserver("StartEvent", lambda *_a: self.starts.append(time.perf_counter()))
        plotter.render_window.AddObserver("EndEvent", lambda *_a: self.renders.append(time.perf_counter()))
        plotter.interactor.frameSwapped.connect(lambda: self.swaps.append(time.perf_counter()))


def stats(values, unit: str = "ms", scale: float = 1e3) -> str:
    import numpy as np

    v = np.asarray(values, float) * scale
    if v.size == 0:
        return "no samples"
    return f"min {v.min():.1f} {unit}, median {np.median(v):.1f} {unit}, max {v.max():.1f} {unit} (n={v.size})"
