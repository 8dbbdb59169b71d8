"""Shared set-up of the GUI benchmarks (bench_gui_click.py, bench_gui_playback.py, bench_gui_startup.py).

They drive the real explorer window (``app.main_window.MainWindow``) under an X server.
Without a DISPLAY a script re-runs itself under ``xvfb-run -a -s "-screen 0 1600x1200x24"``
(software OpenGL: Mesa llvmpipe). The default synthetic talker's manifold (28,800 frames)
is built once into the cache (``$LIPSPACE_CACHE_DIR`` or the user cache dir) if missing.

``--manifold FILE`` (several may be given) runs a script on any built manifold instead,
blocked corpora's included (``tools/make_standins.py`` builds the 100k-1M stand-ins);
``talker`` names the default talker, so that both can be measured side by side in one run
(:func:`manifold_specs`, :func:`load_manifold`, :func:`compare`).
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
    print(f"   {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at start, "
          f"DISPLAY={os.environ.get('DISPLAY')}")


def default_manifold(preset: str = "default"):
    """The synthetic talker's manifold from the explorer's cache (built and cached when missing)."""
    try:
        from app.files.source_loading import cached_manifold_path, load_source
    except ImportError:  # trees before app.files.source_loading (bench_gui_playback.py --tree)
        from app.cli.explore import cached_manifold_path, load_source

    path = cached_manifold_path(preset)
    how = "loaded from" if path.exists() else "built; cache"  # asked before loading writes the cache
    t = time.perf_counter()
    m, src = load_source(None, preset)
    print(f"   manifold: synthetic talker '{preset}', {m.Fy_.shape[0]} frames, {how} {path} "
          f"({time.perf_counter() - t:.1f} s)")
    return m, src


#: what ``--manifold`` calls the default synthetic talker
TALKER = "talker"


def add_manifold_argument(ap) -> None:
    """``--manifold FILE [FILE ...]`` (``talker``: the default synthetic talker)."""
    ap.add_argument("--manifold", nargs="+", default=None, metavar="FILE",
                    help="manifold file(s) from 'lipspace build' (any size, blocked corpora included); "
                         f"'{TALKER}' is the default synthetic talker; several are measured side by side, "
                         "each in fresh processes, in alternating order")
    ap.add_argument("--max-points", type=int, default=None,
                    help="points the manifold view draws at most (app.models.lod.DEFAULT_MAX_POINTS; "
                         "default its value)")


def parse_bench_args(ap):
    """Add ``--preset``, ``--manifold``, ``--max-points`` and the hidden ``--child``; parse; make sure there is a
    display (:func:`ensure_display`) and apply ``--max-points``. Returns ``(args, cap)``, ``cap`` the option to
    pass on to child processes."""
    import argparse

    ap.add_argument("--preset", default="default", help="the synthetic talker's preset ('talker')")
    add_manifold_argument(ap)
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    ensure_display()
    return args, apply_max_points(args)


def apply_max_points(args) -> list[str]:
    """Set the level of detail's cap from ``--max-points`` (in this process); returns the option for children."""
    if args.max_points is None:
        return []
    import app.models.lod

    app.models.lod.DEFAULT_MAX_POINTS = int(args.max_points)
    return ["--max-points", str(args.max_points)]


def manifold_specs(args) -> list[str]:
    """The manifolds a run measures: ``--manifold``'s, else the talker of ``--preset``."""
    if not args.manifold:
        return [TALKER]
    out = []
    for spec in args.manifold:
        if spec != TALKER and not os.path.isfile(spec):
            sys.exit(f"--manifold {spec}: no such file (build one with 'lipspace build' or tools/make_standins.py)")
        out.append(spec if spec == TALKER else os.path.abspath(spec))
    return out


def spec_label(spec: str) -> str:
    return TALKER if spec == TALKER else os.path.basename(spec)


def load_manifold(spec: str, preset: str = "default"):
    """``(manifold, source)`` for a ``--manifold`` entry, loaded as the window loads it (views prepared)."""
    if spec == TALKER:
        return default_manifold(preset)
    from app.files.source_loading import load_source

    t = time.perf_counter()
    m, src = load_source(spec)
    print(f"   manifold: {spec}, {m.Fy_.shape[0]} frames, K={m.states_.centroids_.shape[0]}, loaded and prepared in "
          f"{time.perf_counter() - t:.1f} s", flush=True)
    return m, src


def order_of_runs(specs, repeats: int) -> list[str]:
    """Each manifold ``repeats`` times, the order reversed every other round (side by side, alternating)."""
    out = []
    for r in range(repeats):
        out += specs if r % 2 == 0 else specs[::-1]
    return out


def run_marked_child(cmd, spec: str, mark: str = "RESULT") -> dict:
    """Run a benchmark's child process on manifold ``spec``; the JSON it printed after ``mark``
    (exits naming the manifold, with the end of the child's output, when it failed)."""
    import json

    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, env=os.environ)
    line = [ln for ln in p.stdout.splitlines() if ln.startswith(mark + " ")]
    if p.returncode != 0 or not line:
        sys.exit(f"child on {spec} failed ({p.returncode}):\n{p.stdout[-2000:]}\n{p.stderr[-3000:]}")
    return json.loads(line[0][len(mark) + 1:])


def compare(label: str, per_spec: dict, unit: str = "ms", scale: float = 1e3, *, bench=None, **figure) -> None:
    """Print min / median per manifold of the values ``per_spec[spec]`` (one per run or click) and, against
    the first manifold, the ratio of their medians and of their minima; with ``bench`` (a
    :class:`_harness.Harness`) each manifold's values become a figure (in seconds when ``unit`` is a time),
    ``figure`` passed to :meth:`~_harness.Harness.figure`."""
    import numpy as np

    specs = list(per_spec)
    base = specs[0]
    for spec in specs:
        v = np.asarray(per_spec[spec], float) * scale
        if v.size == 0:
            continue
        line = (f"   {label} [{spec_label(spec)}]: min {v.min():.1f} {unit}, median {np.median(v):.1f} {unit} "
                f"(n={v.size})")
        b = np.asarray(per_spec[base], float) * scale
        if spec != base and b.size:

            def ratio(x, y):
                return f"{x / y:.2f}" if y else "n/a"

            line += f"; / {spec_label(base)}: median {ratio(np.median(v), np.median(b))}, min {ratio(v.min(), b.min())}"
        print(line)
        if bench is not None:
            secs = {"ms": 1e-3, "s": 1.0}.get(unit)  # a time is kept in seconds
            bench.figure(f"{label} [{spec_label(spec)}]", list(v * secs) if secs else list(v), "s" if secs else unit,
                         show=False, **figure)


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
