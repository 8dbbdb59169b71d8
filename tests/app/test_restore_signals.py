"""A stop signal while the restore question is open ends the explorer cleanly (issue 39 item 8): exit
128 + signal within seconds, one line, no KeyboardInterrupt traceback from the autosave tick, no process
left running (before, only kill -9 ended it)."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import textwrap
import time

import pytest

pytestmark = pytest.mark.gui

SCRIPT = textwrap.dedent("""
    import sys
    import app.launching as mw

    ask = mw.ask_restore

    def asking(recovery, parent=None):
        print("asking", flush=True)
        return ask(recovery, parent)

    mw.ask_restore = asking
    from app.cli import main
    sys.exit(main(["explore", sys.argv[1]]))
""")


@pytest.fixture
def crashed_run(tmp_path, app_manifold):
    """A manifold file and a state folder holding a dead run's marker and autosave of it."""
    m = app_manifold.save(tmp_path / "m.npz")
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    a = tmp_path / "state" / "autosave"
    a.mkdir(parents=True)
    (a / f"running-{p.pid}-5.json").write_text(json.dumps({"pid": p.pid, "started": time.time() - 60}))
    (a / f"autosave-{p.pid}-5.lipspace.json").write_text(json.dumps({"lipspace_session": 2,
                                                                     "source": {"path": str(m)}}))
    return m


@pytest.mark.parametrize("signame", ["SIGINT", "SIGTERM"])
def test_a_stop_signal_during_the_restore_question_ends_the_explorer(crashed_run, tmp_path, signame,
                                                                    signal_when_ready, explore_env):
    # 1.5 s after "asking": the question's own event loop is running (and the autosave timer with it)
    code, _, err, took = signal_when_ready([sys.executable, "-c", SCRIPT, str(crashed_run)], explore_env,
                                           ready="asking", signum=getattr(signal, signame), delay=1.5, timeout=30)
    assert code == 128 + getattr(signal, signame), err
    assert took < 10 and "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert err.strip().endswith(f"lipspace explore: stopped by {signame}; the window was closed (nothing was "
                                "autosaved yet)."), err
    assert list((tmp_path / "state" / "autosave").glob("autosave-*-5.lipspace.json"))  # still offered next time


BUSY = textwrap.dedent("""
    import sys, time
    import app.main_window as mw
    import app.workers as workers
    from app.cli import main

    workers_cancel_all = workers.cancel_all
    workers.cancel_all = lambda timeout_ms=5000: workers_cancel_all(timeout_ms=300)  # a long step outlasts the wait

    def busy(progress):
        progress(0.0, "fitting")
        time.sleep(30)  # one engine step without a progress call (a large eigendecomposition)
        progress(1.0, "done")

    def open_source(self, *args, **kwargs):
        workers.run_task(busy, parent=self, dialog=False)
        print("busy", flush=True)

    mw.MainWindow.open_source = open_source
    sys.exit(main(["explore", sys.argv[1]]))
""")


def test_a_stop_signal_while_a_task_is_inside_an_engine_step_exits_with_its_code(tmp_path, app_manifold,
                                                                                 signal_when_ready, explore_env):
    """Closing the window cancels the loading task, but one inside a long engine step cannot stop at once:
    the process must still end with 128 + signal (before: Qt aborted it, 'QThread: Destroyed while thread
    is still running', a core dump)."""
    m = app_manifold.save(tmp_path / "m.npz")
    code, _, err, took = signal_when_ready([sys.executable, "-c", BUSY, str(m)], explore_env, ready="busy",
                                           signum=signal.SIGTERM, delay=1.0, timeout=60)
    assert code == 128 + signal.SIGTERM, err
    assert took < 20 and "QThread: Destroyed" not in err and "Traceback" not in err, err
    assert err.strip().endswith("lipspace explore: stopped by SIGTERM; the window was closed (nothing was "
                                "autosaved yet)."), err
