import numpy as np
import pytest

from app.cli import main
from engine.manifold import Manifold


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("build") / "m.npz"
    assert main(["build", "--preset", "small", "-o", str(out), "-q"]) == 0
    return out


def test_build_writes_a_loadable_manifold(built, small_corpus):
    m = Manifold.load(built)
    assert m.Fy_.shape == (small_corpus.n_frames, 10)
    assert m.corpus_.n_frames == small_corpus.n_frames


def test_info_reports_classes_and_connectivity(built, capsys):
    assert main(["info", str(built)]) == 0
    out = capsys.readouterr().out
    assert "Lipspace manifold" in out
    assert "opening/accelerating" in out and "closing/decelerating" in out
    assert "first 3 dims hold" in out
    pcts = [float(t.split()[-1].rstrip("%;")) for t in out.split("classes")[1].splitlines()[0].split(";")]
    assert abs(sum(pcts) - 100) < 0.5


def test_info_on_corpus_file(tmp_path, small_corpus, capsys):
    p = small_corpus.save(tmp_path / "c.npz")
    assert main(["info", str(p)]) == 0
    out = capsys.readouterr().out
    assert "Lipspace corpus" in out and f"{small_corpus.n_frames} at 60 Hz" in out


def test_cli_errors_are_clean(tmp_path, capsys):
    assert main(["info", str(tmp_path / "nope.npz")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["build", "-o", str(tmp_path / "x.txt")]) == 2
    bad = tmp_path / "bad.npz"
    np.savez(bad, x=np.zeros(2))
    assert main(["build", str(bad), "-o", str(tmp_path / "m.npz"), "-q"]) == 2
    assert "not a Lipspace corpus" in capsys.readouterr().err
    assert not (tmp_path / "m.npz").exists()


def test_ctrl_c_stops_build_cleanly_and_writes_nothing(tmp_path):
    """A real SIGINT to `lipspace build` mid-fit: exit 130, one line, no traceback, no file."""
    import os
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "m.npz"
    proc = subprocess.Popen([sys.executable, "-m", "app.cli", "build", "--preset", "default", "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=dict(os.environ))
    time.sleep(3.0)  # generating the talker or fitting: either way mid-work
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    err_head = err[-2000:]
    assert proc.returncode == 130, err_head
    assert "interrupted; nothing was written" in err and "Traceback" not in err, err_head
    assert not out.exists() and not list(tmp_path.glob(".*part*"))
