import numpy as np
import pytest

from app.cli import main
from engine.manifold.model import Manifold


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("build") / "m.npz"
    assert main(["build", "--preset", "small", "-o", str(out), "-q"]) == 0
    return out


def test_build_writes_a_loadable_manifold(built, small_corpus):
    m = Manifold.load(built)
    assert m.Fy_.shape == (small_corpus.n_frames, 16)
    assert m.corpus_.n_frames == small_corpus.n_frames


def test_info_reports_classes_and_connectivity(built, capsys):
    assert main(["info", str(built)]) == 0
    out = capsys.readouterr().out
    assert "Lipspace manifold" in out
    assert "opening/accelerating" in out and "closing/decelerating" in out
    assert "first 3 dims hold" in out
    # the two scree figures, each named, agree with the fitted shape space
    sh = Manifold.load(built).shape_
    n_rec = int(np.argmax(sh.recovered_ratio_ >= 0.95 - 1e-12)) + 1
    total = f"{int(np.argmax(np.cumsum(sh.scree_) >= 0.95 - 1e-12)) + 1}" if sh.scree_.sum() >= 0.95 \
        else f"more than {len(sh.scree_)}"
    assert f"95% of the total variance takes {total} components" in out
    assert f"95% of the {len(sh.scree_)} computed components' variance (the paper's \"recovered variance\") " \
           f"takes {n_rec}" in out
    pcts = [float(t.split()[-1].rstrip("%;")) for t in out.split("classes")[1].splitlines()[0].split(";")]
    assert abs(sum(pcts) - 100) < 0.5


def test_built_talker_speaks_as_the_explorers_does_or_info_says_why(built, capsys):
    """`lipspace build` of the synthetic talker keeps its speech audio (README: the talker speaks when
    espeak-ng is installed; without it `info` says why in its history line). Before, the built file was
    silent with espeak-ng installed and its history said nothing."""
    from pathlib import Path

    c = Manifold.load(built).corpus_
    audio = [u.audio for u in c.utterances]
    if all(audio):
        assert all(Path(a).is_file() for a in audio)
        assert any(h.startswith("speech audio: espeak-ng") for h in c.history), c.history
    else:
        assert not any(audio) and any(h.startswith("speech audio: none;") for h in c.history), c.history
    assert main(["info", str(built)]) == 0
    assert "history     speech audio: " in capsys.readouterr().out


def test_info_on_corpus_file(tmp_path, small_corpus, capsys):
    p = small_corpus.save(tmp_path / "c.npz")
    assert main(["info", str(p)]) == 0
    out = capsys.readouterr().out
    assert "Lipspace corpus" in out and f"{small_corpus.n_frames} at 60 Hz" in out
    assert f"s), {len(small_corpus.utterances)} utterances\n" in out


def test_info_counts_one_utterance_in_the_singular(tmp_path, small_corpus, capsys):
    one = small_corpus.subset([small_corpus.utterances[0].id])
    assert main(["info", str(one.save(tmp_path / "one.npz"))]) == 0
    frames_line = next(ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("frames"))
    assert frames_line.endswith("s), 1 utterance"), frames_line


def test_cli_errors_are_clean(tmp_path, capsys):
    assert main(["info", str(tmp_path / "nope.npz")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["build", "-o", str(tmp_path / "x.txt")]) == 2
    bad = tmp_path / "bad.npz"
    np.savez(bad, x=np.zeros(2))
    assert main(["build", str(bad), "-o", str(tmp_path / "m.npz"), "-q"]) == 2
    assert "not a Lipspace corpus" in capsys.readouterr().err
    assert not (tmp_path / "m.npz").exists()


def test_ctrl_c_stops_build_cleanly_and_writes_nothing(tmp_path, running_build):
    """A real SIGINT to `lipspace build` mid-fit: exit 130, one line, no traceback, no file."""
    import signal

    out = tmp_path / "m.npz"
    build = running_build(["--preset", "default", "-o", out])
    build.wait_until_fitting()  # it has said its plan: the fit is under way
    build.proc.send_signal(signal.SIGINT)
    err = build.finish(timeout_s=60)
    err_head = err[-2000:]
    assert build.proc.returncode == 130, err_head
    assert "interrupted; nothing was written" in err and "Traceback" not in err, err_head
    assert not out.exists() and not list(tmp_path.glob(".*part*"))


# ------------------------------------------------------------------ no data loss (issue 16)
def _digest(p):
    import hashlib

    return hashlib.sha256(p.read_bytes()).hexdigest()


def test_build_refuses_to_overwrite_its_own_input(tmp_path, small_corpus, capsys):
    """`build corpus.npz -o corpus.npz` used to replace the corpus by a manifold without frames."""
    c = small_corpus.save(tmp_path / "corpus.npz")
    (tmp_path / "link.npz").symlink_to(c)
    before = _digest(c)
    for out in (c, tmp_path / "link.npz"):
        assert main(["build", str(c), "-o", str(out), "-q"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "is also an input" in err, err
    assert _digest(c) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["corpus.npz", "link.npz"]


def test_outputs_of_the_wrong_kind_are_one_line_errors(tmp_path, built, capsys):
    (tmp_path / "afile").write_text("x")
    cases = [["build", "-o", str(tmp_path), "-q"],
             ["synthesize", "--manifold", str(built), "--phones", "p 0.1 aa 0.2", "--mesh-dir",
              str(tmp_path / "afile"), "-q"],
             ["synthesize", "--manifold", str(built), "--phones", "p 0.1 aa 0.2", "-o", str(tmp_path), "-q"]]
    for argv in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.startswith(f"lipspace {argv[0]}: error:") and err.count("\n") == 1, err


def test_fifo_input_is_refused_without_blocking(tmp_path, capsys):
    import os

    fifo = tmp_path / "pipe.npz"
    os.mkfifo(fifo)
    for argv in (["info", str(fifo)], ["build", str(fifo), "-o", str(tmp_path / "m.npz"), "-q"]):
        assert main(argv) == 2
        assert "not a regular file" in capsys.readouterr().err
    assert not (tmp_path / "m.npz").exists()


def test_disk_full_is_one_line_and_leaves_no_file(tmp_path, built, capsys, monkeypatch):
    import errno

    def full(fh, arr, **kw):
        fh.write(b"\x93NUMPY partial")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np, "save", full)
    out = tmp_path / "t.npy"
    assert main(["synthesize", "--manifold", str(built), "--phones", "p 0.1 aa 0.2", "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert "No space left on device" in err and "disk is full" in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_memory_error_is_one_line_with_a_hint(tmp_path, small_corpus, capsys, monkeypatch):
    from engine.manifold.model import Manifold

    def oom(self, corpus, progress=None, **kwargs):
        raise MemoryError("Unable to allocate 15.6 GiB for an array with shape (461000, 4540) and data type float64")

    monkeypatch.setattr(Manifold, "fit", oom)
    c = small_corpus.save(tmp_path / "c.npz")
    assert main(["build", str(c), "-o", str(tmp_path / "m.npz"), "-q"]) == 2
    err = capsys.readouterr().err
    # 15.6 GiB said in the user's units (16.8 GB), never numpy's array shape and dtype
    assert err.count("\n") == 1 and "16.8 GB" in err and "--landmarks 2000" in err and "--resample" in err
    assert "shape" not in err and "float64" not in err


def test_interrupted_mesh_export_leaves_nothing(tmp_path, built, capsys, monkeypatch):
    """Ctrl-C part-way through --mesh-dir used to leave frame files while saying nothing was written, and the
    trajectory written before them (-o t.csv); the old trajectory stays."""
    import engine.io.writers.export as export

    real, calls = export.write_obj, []

    def interrupted(*a, **kw):
        calls.append(1)
        if len(calls) == 4:
            raise KeyboardInterrupt
        return real(*a, **kw)

    monkeypatch.setattr(export, "write_obj", interrupted)
    mesh, old = tmp_path / "meshes", tmp_path / "t.csv"
    old.write_text("the user's trajectory")
    argv = ["synthesize", "--manifold", str(built), "--phones", "p 0.1 aa 0.2 m 0.1", "--mesh-dir", str(mesh), "-q",
            "-o", str(old), "--force"]
    assert main(argv) == 130
    assert capsys.readouterr().err.strip().endswith("interrupted; nothing was written.")
    assert list(tmp_path.iterdir()) == [old] and old.read_text() == "the user's trajectory"
    monkeypatch.setattr(export, "write_obj", real)
    assert main(argv) == 0
    assert len(list(mesh.iterdir())) > 4 and sorted(tmp_path.iterdir()) == [mesh, old]
    assert old.read_text().startswith("time,")


@pytest.mark.parametrize("signame", ["SIGTERM", "SIGHUP"])
def test_sigterm_and_sighup_stop_build_like_ctrl_c(tmp_path, running_build, signame):
    """They used to kill the process and leave 130-190 MB hidden .part files."""
    import signal

    out = tmp_path / "m.npz"
    build = running_build(["--preset", "default", "-o", out])
    build.wait_until_fitting()
    sig = getattr(signal, signame)
    build.proc.send_signal(sig)
    err = build.finish(timeout_s=60)
    assert build.proc.returncode == 128 + sig, err[-2000:]
    assert f"stopped by {signame}; nothing was written" in err and "Traceback" not in err, err[-2000:]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv,limit", [
    (["figures", "{m}", "-o", "{tmp}/figs", "--dpi", "100000", "-q"], "at most 1200"),
    (["figures", "{m}", "-o", "{tmp}/figs", "--dpi", "nan", "-q"], "from 10 to 1200"),
    (["import", "{m}", "-o", "{tmp}/c.npz", "--resample", "1e9"], "at most 2000 Hz"),
    (["import", "{m}", "-o", "{tmp}/c.npz", "--resample", "-5"], "at most 2000 Hz"),
])
def test_resource_arguments_are_bounded_with_the_limit_in_the_message(tmp_path, built, capsys, argv, limit):
    argv = [a.format(m=built, tmp=tmp_path) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and limit.replace("at most ", "") in err, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("extra,limit", [
    (["--phones", "p 1e6 aa 0.1"], "at most 600 s"),
    (["--text", "hello world", "--tempo", "1e-6"], "from 0.1 to 10"),
    (["--phones", "p 0.1 aa 0.1", "--inverse-dims", "10"], "from 1 to 5"),
    (["--text", "  "], "--text '  ': expected a value, not an empty string"),
])
def test_synthesis_that_would_hang_is_refused_with_the_limit(tmp_path, built, capsys, extra, limit):
    """These used to run past 60-180 s (tens of millions of frames, a 10-D Delaunay of 3.6 GB)."""
    out = tmp_path / "t.csv"
    assert main(["synthesize", "--manifold", str(built), *extra, "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and limit in err, err
    assert not out.exists()


def test_names_with_terminal_escape_codes_are_printed_escaped(tmp_path, small_corpus, capsys):
    from dataclasses import replace

    c = replace(small_corpus.subset([small_corpus.utterances[0].id]), name="evil\x1b]0;owned\x07\x1b[2J")
    p = c.save(tmp_path / "c.npz")
    assert main(["info", str(p)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "evil\\x1b]0;owned\\x07\\x1b[2J" in out


def test_dynamics_scale_option_is_validated(tmp_path, small_corpus, capsys):
    c = small_corpus.save(tmp_path / "c.npz")
    out = tmp_path / "m.npz"
    assert main(["build", str(c), "-o", str(out), "-q", "--dynamics-scale", "p200"]) == 2
    err = capsys.readouterr().err
    assert "error: --dynamics-scale must be 'max' or a percentile 'pQ'" in err and "got 'p200'" in err
    assert not out.exists()


def test_a_subcommand_imports_only_its_own_module():
    """`lipspace synthesize` used to import the figure modules (matplotlib) to build its parser."""
    import subprocess
    import sys

    code = ("import sys; from app.cli import build_parser; build_parser('synthesize'); "
            "print(sorted(m for m in ('app.cli.figures', 'app.figures', 'matplotlib', 'app.cli.synthesize') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "['app.cli.synthesize']"


def test_top_level_help_imports_no_command_and_no_numpy():
    """`lipspace --help` built every subcommand's parser (matplotlib, numpy: 26x bare Python's start-up)."""
    import subprocess
    import sys

    code = ("import sys; from app.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit as e:\n    assert e.code == 0, e.code\n"
            "print(sorted(m for m in sys.modules if m.startswith('app.cli.') or m.split('.')[0] in "
            "('numpy', 'matplotlib', 'scipy')), file=sys.stderr)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "synthesize" in r.stdout and "cache" in r.stdout  # every command listed
    assert r.stderr.strip() == "[]", r.stderr


def test_build_the_calibrated_talker_keeps_the_classic_cache(tmp_path, monkeypatch, capsys):
    """``lipspace build --kinematics calibrated`` builds the opt-in talker; the cache keeps the
    classic talker's corpus beside it (each variant has its own file name), and a corpus file
    with --kinematics is refused with the reason."""
    from app.files.cache import entries
    from engine.talker.synthetic import load_synthetic

    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path / "cache"))
    classic = load_synthetic(preset="small")
    out = tmp_path / "cal.npz"
    assert main(["build", "--preset", "small", "--kinematics", "calibrated", "-o", str(out), "-q"]) == 0
    m = Manifold.load(out)
    jf = m.corpus_.latent["jaw_forward"]
    assert np.ptp(jf) > 0.5 and np.ptp(classic.latent["jaw_forward"]) == 0.0
    corpora = sorted(e.preset for e in entries(tmp_path / "cache") if e.kind == "corpus")
    assert corpora == ["small", "small_calibrated"]
    assert main(["build", "--preset", "small", "-o", str(tmp_path / "c.npz"), "-q"]) == 0   # classic: both stay
    assert sorted(e.preset for e in entries(tmp_path / "cache") if e.kind == "corpus") == corpora
    p = classic.save(tmp_path / "corpus.npz")
    assert main(["build", str(p), "--kinematics", "calibrated", "-o", str(tmp_path / "x.npz")]) == 2
    assert "--kinematics chooses the synthetic talker's" in capsys.readouterr().err

