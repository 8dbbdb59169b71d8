"""Nothing a user hands over crashes, hangs, leaks memory or leaves a file (issue 16).

Two parts:

* concrete hostile files found by the bad-input campaign, each run as a real
  ``lipspace`` process under a memory cap and a timeout: exit 2, one line, no
  traceback, no output file;
* a bounded hypothesis fuzz of every batch command's arguments and of the three
  loaders (manifold, corpus, session): exit 0 or 2 (argparse's usage error is 2 as
  well), never an exception, never an output file after a failure, each case within
  a deadline.
"""
from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app.cli import main

MEMORY_CAP = 3 * 2**30  # address space of each hostile run (the bombs wanted 6-19 GB)
FUZZ = settings(max_examples=25, deadline=60_000, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def _run_capped(argv, cwd, timeout=90):
    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))

    t = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "app.cli", *argv], capture_output=True, text=True, cwd=cwd,
                       timeout=timeout, preexec_fn=cap, env=dict(os.environ))
    return r, time.perf_counter() - t


# ------------------------------------------------------------------ hostile files
def _est_claiming_2e9_channels(d):
    p = d / "huge.ema"
    p.write_bytes(b"EST_File Track\nDataType binary\nByteOrder 01\nNumFrames 1\nNumChannels 2000000000\n"
                  b"BreaksPresent true\nEST_Header_End\n" + bytes(36_000))
    return p, "damaged header"


def _mat_zlib_bomb(d):
    """A MAT-file whose one compressed variable inflates to 160 MiB from 160 KB (the campaign's: 5.9 GB)."""
    c = zlib.compressobj(9)
    chunks = [c.compress(bytes(2**20)) for _ in range(160)] + [c.flush()]
    payload = b"".join(chunks)
    head = b"MATLAB 5.0 MAT-file, hostile".ljust(116, b" ") + bytes(8) + b"\x00\x01IM"
    p = d / "bomb.mat"
    p.write_bytes(head + np.array([15, len(payload)], "<u4").tobytes() + payload)
    return p, "decompression bomb"


def _npz_zip_bomb(d):
    import zipfile

    p = d / "bomb.npz"
    with zipfile.ZipFile(p, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        with zf.open("corpus_frames.npy", "w", force_zip64=True) as f:
            np.lib.format.write_array_header_1_0(f, {"descr": "<f4", "fortran_order": False, "shape": (40 * 2**20,)})
            for _ in range(160):
                f.write(bytes(2**20))
    return p, "decompression bomb"


def _ply_of_empty_rows(d):
    n = 5_000_000
    hdr = (f"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
           f"property float z\nelement face {n}\nproperty list uchar int vertex_indices\nend_header\n").encode()
    (d / "frames").mkdir()
    for k in range(2):
        (d / "frames" / f"frame_{k}.ply").write_bytes(hdr + bytes(36) + bytes(n))
    return d / "frames", "0 vertices"


@pytest.mark.parametrize("make,command", [
    (_est_claiming_2e9_channels, "import"), (_mat_zlib_bomb, "import"), (_npz_zip_bomb, "info"),
    (_npz_zip_bomb, "build"), (_ply_of_empty_rows, "import"),
], ids=["est-2e9-channels", "mat-zlib-bomb", "npz-zip-bomb-info", "npz-zip-bomb-build", "ply-empty-rows"])
def test_hostile_file_is_one_line_error_within_bounds(tmp_path, make, command):
    src, expected = make(tmp_path)
    out = tmp_path / "out" / "result.npz"
    argv = {"import": ["import", str(src), "-o", str(out), "--rate", "60"], "info": ["info", str(src)],
            "build": ["build", str(src), "-o", str(out), "-q"]}[command]
    r, wall = _run_capped(argv, tmp_path)
    assert r.returncode == 2, r.stderr[-3000:]
    assert r.stderr.startswith(f"lipspace {command}: error:") and expected in r.stderr, r.stderr[-3000:]
    assert "Traceback" not in r.stderr and r.stderr.count("\n") == 1, r.stderr[-3000:]
    assert not out.parent.exists() or not list(out.parent.iterdir())
    assert wall < 60, f"{wall:.0f} s"


# ------------------------------------------------------------------ fixtures for the fuzz
@pytest.fixture(scope="module")
def files(small_corpus, tmp_path_factory):
    """A tiny corpus and its manifold (fast to load and synthesise from), a directory, a FIFO, junk."""
    from engine.manifold.model import Manifold

    d = tmp_path_factory.mktemp("fuzz-inputs")
    tiny = small_corpus.subset([u.id for u in small_corpus.utterances[:3]])
    corpus = tiny.save(d / "corpus.npz")
    manifold = Manifold(n_states=20).fit(tiny).save(d / "manifold.npz")
    (d / "junk.npz").write_bytes(b"PK\x03\x04 not really")
    (d / "text.csv").write_text("frame,x,y\n0,1,2\n1,nan,3\n")
    (d / "adir").mkdir()
    os.mkfifo(d / "fifo.npz")
    assert main(["info", str(manifold)]) == 0  # imports warmed up: the deadline times the case, not start-up
    return {"corpus": corpus, "manifold": manifold, "junk": d / "junk.npz", "csv": d / "text.csv",
            "dir": d / "adir", "fifo": d / "fifo.npz", "missing": d / "missing.npz"}


def _inputs(files):
    return st.sampled_from(["corpus", "manifold", "junk", "csv", "dir", "fifo", "missing"]).map(
        lambda k: str(files[k]))


NUMBERS = st.sampled_from(["0", "-1", "1", "3", "1e9", "-1e9", "nan", "inf", "1e-6", "0.5", "x", "", "100000"])
TEXT = st.text(alphabet=st.characters(codec="utf-8", exclude_categories=("Cs",)), max_size=30)


def _call(argv):
    """main(argv) -> exit code; argparse's usage errors (SystemExit 2) count as 2."""
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code


def _check(argv, outdir: Path, code):
    assert code in (0, 2), (argv, code)
    if code != 0:
        left = [p for p in outdir.rglob("*")]
        assert not left, (argv, left)


# ------------------------------------------------------------------ silent acceptance / misreports
@pytest.mark.parametrize("text, expected", [
    ("café", "the word 'café' is not in"),          # was reported as unknown word 'caf'
    ("Zoë's naïve", "the word \"Zoë's\" is not in"),
    ("...", "no words in the text '...'"),          # was synthesised as silence with exit 0
    ("[]", "no words in the text '[]'"),
    ("   ", "--text '   ': expected a value, not an empty string"),
])
def test_text_that_says_nothing_is_refused_naming_the_whole_word(files, tmp_path, capsys, text, expected):
    out = tmp_path / "t.csv"
    assert main(["synthesize", "--manifold", str(files["manifold"]), "--text", text, "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lipspace synthesize: error:") and expected in err and err.count("\n") == 1, err
    assert not out.exists()


def test_info_on_a_recording_says_what_it_is_and_how_to_import_it(shared_data, tmp_path, capsys):
    """Not numpy's 'not a zip file' / allow_pickle hint: the format, and 'lipspace import' first."""
    for f, fmt in [(shared_data / "haskins-ieee" / "F01_B01_S01_R01_N.mat", "'mview'"),
                   (shared_data / "mocha-fsew0" / "fsew0_001.ema", "'ema'")]:
        assert main(["info", str(f)]) == 2
        err = capsys.readouterr().err
        assert f"a recording in the {fmt} format" in err and f"lipspace import {f} -o corpus.npz" in err, err
        assert "zip" not in err.lower() and "pickle" not in err and err.count("\n") == 1
    (tmp_path / "x.bin").write_bytes(b"\x00\x01junk")
    assert main(["info", str(tmp_path / "x.bin")]) == 2
    assert "not a Lipspace corpus or manifold file" in capsys.readouterr().err


def test_terminal_escape_codes_in_names_are_not_printed_raw(files, tmp_path, capsys):
    """A corpus named with escape sequences (colour, window title, clear screen) is shown escaped."""
    from engine.files.persist import read_npz

    d = read_npz(files["corpus"])
    d["corpus_name"] = np.array("\x1b[31mRED\x1b]0;owned\x07")
    with open(tmp_path / "esc.npz", "wb") as fh:
        np.savez(fh, **d)
    assert main(["info", str(tmp_path / "esc.npz")]) == 0
    cap = capsys.readouterr()
    assert "\\x1b[31mRED\\x1b]0;owned\\x07" in cap.out and "\x1b" not in cap.out + cap.err
    csv = tmp_path / "roles.csv"  # point names reach stderr (import's roles line): escaped there too
    csv.write_text("time,\x1b[2JUL_x,\x1b[2JUL_y\n" + "".join(f"{k / 60:.4f},{k},0\n" for k in range(10)))
    assert main(["import", str(csv), "-o", str(tmp_path / "c.npz"), "--roles", "upper_lip=0"]) == 0
    cap = capsys.readouterr()
    assert "\x1b" not in cap.out + cap.err and "\\x1b[2JUL" in cap.err, cap.err


def test_import_refuses_a_rate_that_contradicts_the_time_column(tmp_path, capsys):
    csv = tmp_path / "t.csv"
    csv.write_text("time,a_x,a_y\n" + "".join(f"{k / 100:.2f},{k},0\n" for k in range(30)))
    out = tmp_path / "c.npz"
    assert main(["import", str(csv), "-o", str(out), "--rate", "60"]) == 2
    err = capsys.readouterr().err
    assert "gives 100 Hz but a rate of 60 Hz was given (--rate)" in err and not out.exists(), err


def test_import_warns_about_frame_gaps_and_a_long_alignment(tmp_path, capsys):
    long = tmp_path / "g.csv"
    long.write_text("frame,point,x,y\n" + "".join(f"{f},m,{f},0\n" for f in range(60) if f not in (7, 8)))
    (tmp_path / "g.lab").write_text("0 0.5 p\n0.5 1.5 aa\n")  # 1.5 s of speech for 1 s of data
    assert main(["import", str(long), "-o", str(tmp_path / "c.npz"), "--rate", "60"]) == 0
    err = capsys.readouterr().err
    assert "4 without a row in the table" in err and "2 of 60 frames (frames 7, 8); interpolated" in err, err
    assert "runs to 1.500 s but the data last 1.000 s" in err, err
    history = main(["info", str(tmp_path / "c.npz")]) == 0 and capsys.readouterr().out
    assert "frames 7, 8" in history and "runs to 1.500 s" in history, history  # info keeps both repairs
    (tmp_path / "g.lab").write_text("0 0.5 p\n0.5 25 aa\n")  # 25x the data: refused
    assert main(["import", str(long), "-o", str(tmp_path / "d.npz"), "--rate", "60"]) == 2
    err = capsys.readouterr().err
    assert "25.0 times as long" in err and not (tmp_path / "d.npz").exists(), err


def test_cli_memory_error_names_the_size(monkeypatch, capsys):
    def build(args):
        return np.empty((10**7, 10**6))

    import app.cli.build as b

    monkeypatch.setattr(b, "run", build)
    assert main(["build", "-o", "x.npz", "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lipspace build: error: out of memory (needed 80000.0 GB more at once") and \
        "--landmarks 2000" in err and err.count("\n") == 1, err


# ------------------------------------------------------------------ CLI fuzz
@FUZZ
@given(data=st.data())
def test_fuzz_info_and_clusters(files, data, capsys):
    cmd = data.draw(st.sampled_from(["info", "clusters"]))
    argv = [cmd, data.draw(_inputs(files))]
    if cmd == "clusters":
        argv += data.draw(st.lists(st.sampled_from([["--dims", "x"], ["--min-count", "y"], ["--phones", "z"],
                                                    ["--measure", "bhattacharyya"], ["--normalize"], ["-q"]]),
                                   max_size=3).map(lambda xs: [a for x in xs for a in x]).flatmap(
            lambda args: st.just([a if a not in "xyz" else "PLACEHOLDER" for a in args])))
        argv = [data.draw(NUMBERS) if a == "PLACEHOLDER" else a for a in argv]
    with tempfile.TemporaryDirectory() as out:
        if cmd == "clusters" and data.draw(st.booleans()):
            argv += ["--csv", str(Path(out) / data.draw(st.sampled_from(["t.csv", "sub/t.csv", "."])))]
        _check(argv, Path(out), _call(argv))
    err = capsys.readouterr().err
    assert "Traceback" not in err


@FUZZ
@given(data=st.data())
def test_fuzz_synthesize(files, data, capsys):
    source = data.draw(st.sampled_from(["--phones", "--text", "--utterance", "--textgrid"]))
    value = data.draw(st.one_of(TEXT, st.sampled_from(["p 0.1 aa 0.2", "p 1e6 aa 0.1", "p -1 aa 0.1",
                                                        "p nan", "aa", "café", "hello world", ""]),
                                _inputs(files)))
    argv = ["synthesize", "--manifold", data.draw(st.sampled_from([str(files["manifold"]), str(files["junk"]),
                                                                   str(files["corpus"])])), source, value, "-q"]
    for opt in data.draw(st.lists(st.sampled_from(["--tempo", "--inverse-dims", "--candidates", "--smoothing"]),
                                  max_size=2, unique=True)):
        argv += [opt, data.draw(NUMBERS)]
    with tempfile.TemporaryDirectory() as out:
        target = data.draw(st.sampled_from(["t.csv", "t.npy", "t.txt", ".", None, "mesh"]))
        if target == "mesh":
            argv += ["--mesh-dir", str(Path(out) / "meshes")]
        elif target is not None:
            argv += ["-o", str(Path(out) / target)]
        _check(argv, Path(out), _call(argv))
    assert "Traceback" not in capsys.readouterr().err


@settings(FUZZ, max_examples=15)
@given(data=st.data())
def test_fuzz_build_import_figures(files, data, capsys):
    cmd = data.draw(st.sampled_from(["build", "import", "figures"]))
    with tempfile.TemporaryDirectory() as out:
        o = Path(out)
        if cmd == "build":
            argv = ["build", data.draw(_inputs(files)), "-o", str(o / data.draw(st.sampled_from(["m.npz", "m.txt"]))),
                    "-q"]
            argv += data.draw(st.sampled_from([[], ["--embedding-dims", "0"], ["--landmarks", "1"],
                                               ["--states", "-1"], ["--variance", "nan"], ["--neighbors", "0"]]))
        elif cmd == "import":
            argv = ["import", data.draw(_inputs(files)), "-o", str(o / "c.npz")]
            argv += data.draw(st.sampled_from([[], ["--resample", "1e9"], ["--resample", "nan"], ["--rate", "-5"],
                                               ["--resample", "native"], ["--format", "csv"]]))
        else:
            argv = ["figures", str(files["manifold"]), "-o", str(o / "figs"), "-q", "--only", "scree",
                    "--dpi", data.draw(st.sampled_from(["50", "100000", "nan", "-1", "0"]))]
        _check(argv, o, _call(argv))
    assert "Traceback" not in capsys.readouterr().err


# ------------------------------------------------------------------ loader fuzz
def _random_array(data):
    kind = data.draw(st.sampled_from(["float", "int", "bool", "str", "scalar", "json", "empty", "huge-int"]))
    n = data.draw(st.integers(0, 5))
    if kind == "float":
        return np.array(data.draw(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=n,
                                           max_size=n)), dtype=np.float64)
    if kind == "int":
        return np.array(data.draw(st.lists(st.integers(-2**40, 2**40), min_size=n, max_size=n)), dtype=np.int64)
    if kind == "bool":
        return np.ones((n, 2), bool)
    if kind == "str":
        return np.array([data.draw(TEXT) for _ in range(n)], dtype=str)
    if kind == "scalar":
        return np.array(data.draw(st.one_of(st.integers(-2**31, 2**31), st.floats(), TEXT)))
    if kind == "json":
        return np.array(json.dumps(data.draw(st.recursive(
            st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | TEXT,
            lambda c: st.lists(c, max_size=3) | st.dictionaries(TEXT, c, max_size=3), max_leaves=8))))
    if kind == "empty":
        return np.zeros((0, 0))
    return np.array([2**62, -2**62])


def _mutated(path, data, n_keys=3):
    from engine.files.persist import read_npz

    d = read_npz(path)
    keys = sorted(d)
    for _ in range(data.draw(st.integers(1, n_keys))):
        key = data.draw(st.sampled_from(keys))
        action = data.draw(st.sampled_from(["replace", "drop", "shift", "transpose"]))
        if action == "drop":
            d.pop(key, None)
        elif action == "shift" and key in d and d[key].dtype.kind in "iu" and d[key].size:
            d[key] = d[key].astype(np.int64) + data.draw(st.sampled_from([1, -1, 10**6, -(10**6)]))
        elif action == "transpose" and key in d and d[key].ndim == 2:
            d[key] = np.ascontiguousarray(d[key].T)
        else:
            d[key] = _random_array(data)
    return d


@FUZZ
@given(data=st.data())
def test_fuzz_manifold_loader(files, data):
    """A damaged manifold either is refused with ManifoldFileError or loads into something that works."""
    from engine.manifold.model import Manifold, ManifoldFileError

    d = _mutated(files["manifold"], data)
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "m.npz"
        with open(p, "wb") as fh:
            np.savez(fh, **d)
        try:
            m = Manifold.load(p)
        except ManifoldFileError as exc:
            assert str(exc).startswith(str(p)) and "\n" not in str(exc)
            return
    # it loaded: everything `lipspace info` and the window touch must work
    m.summary()
    m.states_.future(0)
    m.states_.past(m.states_.centroids_.shape[0] - 1)
    m.states_.connectivity_report()
    m.tangent_.class_proportions()
    m.embedding_.transform(m.G_[:3])


@FUZZ
@given(data=st.data())
def test_fuzz_corpus_loader(files, data):
    from engine.recordings.corpus import Corpus, CorpusError

    d = _mutated(files["corpus"], data)
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "c.npz"
        with open(p, "wb") as fh:
            np.savez(fh, **d)
        try:
            c = Corpus.load(p)
        except CorpusError as exc:
            assert "\n" not in str(exc)
            return
    c.phone_table()
    c.validate()


@FUZZ
@given(doc=st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | TEXT,
                        lambda c: st.lists(c, max_size=3) | st.dictionaries(TEXT, c, max_size=4), max_leaves=10),
       source=st.one_of(st.none(), TEXT, st.integers(), st.sampled_from(["/etc/passwd", "../../../etc/passwd",
                                                                          "fifo.npz", "adir", "corpus.npz"])))
def test_fuzz_session_loader(files, doc, source):
    from app.files.session import SessionError, load_session

    with tempfile.TemporaryDirectory() as tmp:
        p = Path(files["corpus"]).parent / f"s-{os.getpid()}.json"  # beside the fuzz inputs: relative names
        body = doc if isinstance(doc, dict) else {"x": doc}
        body = {"lipspace_session": 1, **body, "source": {"path": source}} if source is not None else body
        try:
            p.write_text(json.dumps(body))
            try:
                d = load_session(p)
            except SessionError as exc:
                assert "\n" not in str(exc)
                assert "root:" not in str(exc)
                return
            src = d["source"]["path"]
            assert src is None or Path(src).suffix in (".npz",) and Path(src).is_file()
        finally:
            p.unlink(missing_ok=True)
            del tmp


# ------------------------------------------------------------------ explore (headless), evaluate, render
@pytest.fixture
def headless_explore(monkeypatch):
    """explore's batch path (argument, file and session checks) without opening a window:
    a display is reported, and the window's launch records what it was given."""
    import types

    launched = []
    fake = types.ModuleType("app.launching")
    fake.launch = lambda path, **kw: launched.append((path, kw)) or 0
    monkeypatch.setitem(sys.modules, "app.launching", fake)
    monkeypatch.setattr("app.cli.explore.has_display", lambda *a, **k: True)
    return launched


@settings(FUZZ, max_examples=20)
@given(data=st.data())
def test_fuzz_explore_headless(files, data, headless_explore, capsys):
    argv = ["explore"]
    if data.draw(st.booleans()):
        argv.append(data.draw(_inputs(files)))
    argv += data.draw(st.sampled_from([[], ["--preset", "small"], ["--preset", "huge"], ["--restore"],
                                       ["--interocular-mm", "nan"]]))
    session = data.draw(st.sampled_from([None, "missing", "junk", "dir", "fifo", "passwd", "good"]))
    with tempfile.TemporaryDirectory() as tmp:
        if session is not None:
            s = Path(tmp) / "s.lipspace.json"
            body = {"junk": "{not json", "passwd": json.dumps({"lipspace_session": 1, "source": {
                "path": "/etc/passwd"}}), "good": json.dumps({"lipspace_session": 1, "source": {
                    "path": str(files["manifold"])}})}.get(session)
            if body is not None:
                s.write_text(body)
            target = {"dir": files["dir"], "fifo": files["fifo"]}.get(session, s)
            argv += ["--session", str(target)]
        n_before = len(headless_explore)
        code = _call(argv)
    err = capsys.readouterr().err
    assert code in (0, 2) and "Traceback" not in err, (argv, code, err)
    assert (code == 0) == (len(headless_explore) == n_before + 1), (argv, code)  # the window opens only if valid
    assert "root:" not in err, err  # never /etc/passwd's content
    if code == 2 and not err.startswith("usage:"):  # argparse's usage error is its own few lines
        assert err.count("\n") == 1, err


@settings(FUZZ, max_examples=12)
@given(data=st.data())
def test_fuzz_evaluate_and_render(files, data, capsys):
    cmd = data.draw(st.sampled_from(["evaluate", "render"]))
    with tempfile.TemporaryDirectory() as out:
        o = Path(out)
        if cmd == "evaluate":
            argv = ["evaluate", data.draw(_inputs(files)), "-q"]
            for opt in data.draw(st.lists(st.sampled_from(["--test-fraction", "--states", "--state-dims", "--seed",
                                                           "--smoothing", "--neighbors", "--test-ids"]),
                                          max_size=2, unique=True)):
                argv += [opt, data.draw(NUMBERS)]
            if data.draw(st.booleans()):
                argv += ["--csv", str(o / data.draw(st.sampled_from(["e.csv", "sub/e.csv", "."])))]
        else:
            argv = ["render", "--manifold", data.draw(_inputs(files)), "-o",
                    str(o / data.draw(st.sampled_from(["r.mp4", "r.txt", "."]))), "-q", "--no-audio"]
            argv += data.draw(st.sampled_from([["--phones", "p -1 aa 0.1"], ["--text", "..."], ["--phones", "p 1e6"],
                                               ["--utterance", "nope"], ["--textgrid", str(files["csv"])]]))
            argv += data.draw(st.sampled_from([[], ["--size", "0x0"], ["--size", "99999x99999"], ["--size", "x"],
                                               ["--crf", "-5"], ["--tempo", "1e-6"], ["--smoothing", "nan"]]))
        _check(argv, o, _call(argv))
    assert "Traceback" not in capsys.readouterr().err


# ------------------------------------------------------------------ every command in a capped process
_DRIVER = r'''
import io, json, os, resource, signal, sys, time, types, traceback
cap, budget, cases = float(sys.argv[1]), float(sys.argv[2]), json.loads(sys.argv[3])
resource.setrlimit(resource.RLIMIT_AS, (int(cap), int(cap)))
os.environ.pop("DISPLAY", None)
fake = types.ModuleType("app.launching")
fake.launch = lambda path, **kw: 0
sys.modules["app.launching"] = fake
import app.cli.explore
app.cli.explore.has_display = lambda *a, **k: True
from app.cli import main

class Hang(BaseException):
    pass

def alarm(*_):
    raise Hang()

for argv, outdir in cases:
    os.makedirs(outdir, exist_ok=True)
    err, old = io.StringIO(), sys.stderr
    sys.stderr = err
    signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, budget)
    t = time.perf_counter()
    escaped = ""
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    except Hang:
        code, escaped = "hang", "hang"
    except BaseException as exc:
        code, escaped = "exception", traceback.format_exc()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        sys.stderr = old
    left = sorted(os.path.relpath(os.path.join(d, f), outdir) for d, _, fs in os.walk(outdir) for f in fs)
    print(json.dumps({"argv": argv, "code": code, "wall": time.perf_counter() - t, "err": err.getvalue()[-2000:],
                      "escaped": escaped[-2000:], "left": left}), flush=True)
'''
CASE_BUDGET = 30.0  # s per case before it counts as a hang


def _campaign(files, tmp):
    """One hostile case per command (and per loader), as the bad-input campaign tried them."""
    big_text = " ".join(["hello"] * 5000)
    m, c, junk, fifo, d = (str(files[k]) for k in ("manifold", "corpus", "junk", "fifo", "dir"))
    session = tmp / "passwd.lipspace.json"
    session.write_text(json.dumps({"lipspace_session": 1, "source": {"path": "../../../../etc/passwd"}}))
    deep = tmp / "deep.lipspace.json"
    deep.write_text('{"lipspace_session": 1, "x": ' + "[" * 100_000 + "]" * 100_000 + "}")
    cases = [
        ["info", fifo], ["info", junk], ["clusters", m, "--dims", "1000000000"], ["build", c, "-o", c],
        ["build", c, "-o", "{out}/m.npz", "--states", "1000000000", "-q"],
        ["build", c, "-o", "{out}/m.npz", "--landmarks", "-3", "-q"],
        ["import", fifo, "-o", "{out}/c.npz"], ["import", files["csv"], "-o", "{out}/c.npz", "--resample", "1e9"],
        ["synthesize", "--manifold", m, "--phones", "p 1e6 aa 0.1", "-o", "{out}/t.csv", "-q"],
        ["synthesize", "--manifold", m, "--text", big_text, "-o", "{out}/t.csv", "-q"],
        ["synthesize", "--manifold", m, "--phones", "p 0.1 aa 0.1", "--mesh-dir", c, "-q"],
        ["synthesize", "--manifold", m, "--phones", "p 0.1", "--inverse-dims", "10", "-o", "{out}/t.csv", "-q"],
        ["evaluate", junk, "-q"], ["evaluate", c, "--test-fraction", "1e9", "-q"],
        ["render", "--manifold", m, "--phones", "p 0.1 aa 0.1", "-o", "{out}/r.mp4", "--size", "100000x100000",
         "-q", "--no-audio"],
        ["figures", m, "-o", "{out}/figs", "--dpi", "100000", "--only", "scree", "-q"],
        ["explore", fifo], ["explore", "--session", str(session)], ["explore", "--session", str(deep)],
        ["explore", m, "--session", d], ["cache", "--clear", "--bogus"],
    ]
    return [([a.format(out=str(tmp / f"out{k}")) if isinstance(a, str) else str(a) for a in argv],
             str(tmp / f"out{k}")) for k, argv in enumerate(cases)]


def test_every_command_under_a_memory_cap_and_a_time_budget(files, tmp_path):
    """Each case: exit 0 or 2, no traceback (nothing escapes main), within CASE_BUDGET s, under MEMORY_CAP of
    address space, and no file in its output folder when it failed."""
    cases = _campaign(files, tmp_path)
    env = dict(os.environ, LIPSPACE_CACHE_DIR=str(tmp_path / "cache"))
    r = subprocess.run([sys.executable, "-c", _DRIVER, str(MEMORY_CAP), str(CASE_BUDGET), json.dumps(cases)],
                       capture_output=True, text=True, timeout=CASE_BUDGET * len(cases) + 120, env=env,
                       cwd=tmp_path)
    results = [json.loads(line) for line in r.stdout.splitlines() if line.startswith("{")]
    assert len(results) == len(cases), (r.returncode, r.stderr[-3000:])  # a crash or OOM kill ends the list
    for res in results:
        where = (res["argv"][:3], res["err"][-500:], res["escaped"][-1500:])
        assert res["code"] in (0, 2), where
        assert "Traceback" not in res["err"] and not res["escaped"], where
        assert res["wall"] < CASE_BUDGET, where
        if res["code"] != 0:
            assert not res["left"], (where, res["left"])
            assert "root:" not in res["err"], where
            assert res["err"].startswith("usage:") or res["err"].count("\n") <= 2, where
