"""CI: open the explorer of the installed package on a manifold file and quit once it is drawn.

Run with the installed environment's Python from outside the checkout (``.ci/check_wheel``), under
a virtual X server: exits 0 when the window showed the manifold, 1 otherwise (the reason on stderr).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path


def main() -> int:
    import app
    import engine

    here = Path(sys.prefix).resolve()
    for mod in (engine, app):
        if not Path(mod.__file__).resolve().is_relative_to(here):
            print(f"{mod.__name__} comes from {mod.__file__}, not from the installed environment {here}",
                  file=sys.stderr)
            return 1
    from PySide6 import QtCore, QtWidgets

    from app.launching import launch
    from app.main_window import MainWindow

    path = sys.argv[1] if len(sys.argv) > 1 else None
    t0, state = time.monotonic(), {"ok": False}
    qapp = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])

    def poll():
        wins = [w for w in qapp.topLevelWidgets() if isinstance(w, MainWindow)]
        if wins and wins[0].state.manifold is not None:
            state["ok"] = True
            print(f"window shows {wins[0].windowTitle()!r} after {time.monotonic() - t0:.1f} s")
        elif time.monotonic() - t0 < 300:
            return
        for w in wins:
            w.close()
        qapp.quit()

    timer = QtCore.QTimer()
    timer.timeout.connect(poll)
    timer.start(200)
    launch(path, restore=False)
    if not state["ok"]:
        print("the window did not show the manifold within 300 s", file=sys.stderr)
    from app.workers import exit_if_tasks_run

    code = 0 if state["ok"] else 1
    exit_if_tasks_run(code)  # as `lipspace explore` leaves a task still inside an engine step
    return code


if __name__ == "__main__":
    raise SystemExit(main())
