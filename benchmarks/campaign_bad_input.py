"""The bad-input campaign of issue 16 as a checklist: every case the issue lists, run as a
real ``lipspace`` process under a memory cap and a timeout, one line per case.

Usage: python benchmarks/campaign_bad_input.py [--root TREE] [--cap-gb 3] [--timeout 60]

``--root`` runs the cases against another checkout of the project (e.g. an older commit
extracted with ``git archive REV | tar -x -C DIR``) to compare before and after; the
inputs are made by that tree's own code. Each line: the verdict, exit status, wall time,
peak resident memory of the case's process, the case and the first line it printed:

* ``ok``          exit 0 or 2 as expected, one clean line, nothing left behind, the
                  expected refusal or warning said
* ``TRACEBACK``   a Python traceback reached the user
* ``CRASH``       killed by a signal (segfault, OOM kill) or the memory cap
* ``HANG``        still running at the timeout
* ``SILENT``      exit 0 where the input should have been refused or warned about
* ``LEFT``        a failed command left a file (or ``.part`` file) behind
* ``MISREPORT``   refused, but without saying what the issue asks it to say

A summary counts each verdict; ``--json`` writes the rows.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SETUP = r'''
import json, sys
import numpy as np
from engine.synthetic import load_synthetic
from engine.manifold import Manifold
d = sys.argv[1]
c = load_synthetic(preset="small")
tiny = c.subset([u.id for u in c.utterances[:3]])
tiny.save(d + "/corpus.npz")
c.save(d + "/small.npz")
Manifold(n_states=20).fit(tiny).save(d + "/manifold.npz")
'''

#: what a refusal must say, per case (substring of stderr); None: any clean refusal
def cases(d: Path):
    """(name, argv or python snippet, expected exit, what stderr must contain, files that must not exist)."""
    import numpy as np

    m, c = str(d / "manifold.npz"), str(d / "corpus.npz")
    out = d / "out"
    arrays = dict(np.load(m, allow_pickle=False))

    def damaged(name, **changes):
        a = dict(arrays)
        for k, v in changes.items():
            if v is None:
                a.pop(k, None)
            else:
                a[k] = v
        p = d / f"{name}.npz"
        with open(p, "wb") as fh:
            np.savez(fh, **a)
        return str(p)

    key = next(k for k in arrays if k.endswith("transition_.indices"))
    bad_csr = damaged("bad-csr", **{key: arrays[key] + 10**6})
    params = "manifold_params"
    bad_json = damaged("bad-json", **{params: np.array("{not json")})
    as_list = damaged("as-list", **{params: np.array("[1, 2]")})
    unknown = damaged("unknown-key", **{params: np.array(json.dumps({**json.loads(str(arrays[params])),
                                                                       "bogus": 1}))})
    version = damaged("bad-version", manifold_version=np.array("one"))
    lab = next((k for k in arrays if k.endswith("states/labels_")), None)
    labels = damaged("bad-labels", **{lab: arrays[lab] + 1000}) if lab else bad_csr

    est = d / "huge.ema"
    est.write_bytes(b"EST_File Track\nDataType binary\nByteOrder 01\nNumFrames 1\nNumChannels 2000000000\n"
                    b"BreaksPresent true\nEST_Header_End\n" + bytes(36_000))
    co = zlib.compressobj(9)
    payload = b"".join([co.compress(bytes(2**20)) for _ in range(2000)] + [co.flush()])
    mat = d / "bomb.mat"
    mat.write_bytes(b"MATLAB 5.0 MAT-file, hostile".ljust(116, b" ") + bytes(8) + b"\x00\x01IM"
                    + np.array([15, len(payload)], "<u4").tobytes() + payload)
    import zipfile
    npz = d / "bomb.npz"
    with zipfile.ZipFile(npz, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        with zf.open("corpus_frames.npy", "w", force_zip64=True) as f:
            np.lib.format.write_array_header_1_0(f, {"descr": "<f4", "fortran_order": False,
                                                     "shape": (2000 * 2**18,)})
            for _ in range(2000):
                f.write(bytes(2**20))
    ply_dir = d / "ply"
    ply_dir.mkdir(exist_ok=True)
    n = 10 * 2**20
    for k in range(2):  # 10 MB of empty face lists after one triangle (the campaign: 90 s, 1.7 GB)
        (ply_dir / f"f{k}.ply").write_bytes(
            (f"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             f"property float z\nelement face {n}\nproperty list uchar int vertex_indices\nend_header\n").encode()
            + bytes(36) + b"\x03" + np.array([0, 1, 2], "<i4").tobytes() + bytes(n - 1))
    fifo = d / "fifo.npz"
    if not fifo.exists():
        os.mkfifo(fifo)
    csv = d / "timed.csv"
    csv.write_text("time,a_x,a_y\n" + "".join(f"{k / 100:.2f},{k},0\n" for k in range(100)))
    gaps = d / "gaps.csv"
    gaps.write_text("frame,point,x,y\n" + "".join(f"{f},m,{f},0\n" for f in range(60) if f not in (7, 8)))
    lab25 = d / "long.lab"
    lab25.write_text("0 0.5 p\n0.5 25 aa\n")
    ca = np.load(c, allow_pickle=False)
    ca = dict(ca)
    ca["corpus_phone_times"] = ca["corpus_phone_times"] + 1000.0
    ph = d / "phones-out.npz"
    with open(ph, "wb") as fh:
        np.savez(fh, **ca)
    ca2 = dict(np.load(c, allow_pickle=False))
    ca2["corpus_name"] = np.array("\x1b[31mRED\x1b]0;owned\x07")
    esc = d / "escape.npz"
    with open(esc, "wb") as fh:
        np.savez(fh, **ca2)
    shared = ROOT.parent / "shared" / "data"
    (d / "adir").mkdir(exist_ok=True)
    (d / "afile").write_text("x")

    def session(name, body):
        p = d / f"{name}.lipspace.json"
        p.write_text(body if isinstance(body, str) else json.dumps(body))
        return str(p)

    s_passwd = session("passwd", {"lipspace_session": 1, "source": {"path": "/etc/passwd"}})
    s_rel = session("relpasswd", {"lipspace_session": 1, "source": {"path": "../../../../../../etc/passwd"}})
    s_type = session("wrongtype", {"lipspace_session": 1, "source": {"path": 5}})
    s_deep = session("deep", '{"lipspace_session": 1, "x": ' + "[" * 100000 + "]" * 100000 + "}")
    s_range = session("range", {"lipspace_session": 1, "source": {"path": m}, "selection": {"frame": 10**9}})
    s_fifo = session("fifo", {"lipspace_session": 1, "source": {"path": str(fifo)}})
    load = ("from app.session import load_session, SessionError\ntry:\n    d = load_session({!r})\n"
            "except SessionError as exc:\n    print('refused:', exc)\nelse:\n    print('loaded', d['source'])")
    apply = ("from app.session import load_session, apply_session, SessionError\nfrom app.state import AppState\n"
             "from engine.manifold import Manifold\nd = load_session({!r})\n"
             "st = AppState(Manifold.load(d['source']['path']))\ntry:\n    apply_session(st, d)\n"
             "except SessionError as exc:\n    print('refused:', exc)\nelse:\n    print('applied')")
    o = str(out)
    S = "synthesize"
    return [
        ("info: out-of-range CSR indices (segfault)", ["info", bad_csr], 2, None, []),
        ("build corpus -o corpus (destroyed the corpus)", ["build", c, "-o", c, "-q"], 2, "input", []),
        ("info: bad JSON in parameters", ["info", bad_json], 2, None, []),
        ("clusters: parameters a list", ["clusters", as_list], 2, None, []),
        ("synthesize: unknown parameter key", [S, "--manifold", unknown, "--phones", "p 0.1 aa 0.1", "-o",
                                               o + "/t.csv"], 2, None, [o + "/t.csv"]),
        ("info: non-integer version", ["info", version], 2, None, []),
        ("synthesize: labels >= K", [S, "--manifold", labels, "--phones", "p 0.1 aa 0.1", "-o", o + "/t.csv"], 2,
         None, [o + "/t.csv"]),
        ("build -o a directory", ["build", c, "-o", str(d / "adir"), "-q"], 2, None, []),
        ("synthesize --mesh-dir a file", [S, "--manifold", m, "--phones", "p 0.1 aa 0.1", "--mesh-dir",
                                          str(d / "afile")], 2, None, []),
        ("figures --dpi 100000", ["figures", m, "-o", o + "/figs", "--dpi", "100000", "--only", "scree", "-q"], 2,
         None, [o + "/figs"]),
        ("import --resample 1e9", ["import", str(csv), "-o", o + "/c.npz", "--resample", "1e9"], 2, None,
         [o + "/c.npz"]),
        ("SIGTERM during build", ["build", str(d / "small.npz"), "-o", o + "/sig.npz", "-q", "@SIGTERM 4"], None,
         None, [o + "/sig.npz"]),
        ("EST header claiming 2e9 channels", ["import", str(est), "-o", o + "/c.npz", "--rate", "60"], 2, None,
         [o + "/c.npz"]),
        ("MAT zlib bomb (2 GB inflated)", ["import", str(mat), "-o", o + "/c.npz"], 2, None, [o + "/c.npz"]),
        ("npz zip bomb (2 GB inflated): info", ["info", str(npz)], 2, None, []),
        ("npz zip bomb: build", ["build", str(npz), "-o", o + "/m.npz", "-q"], 2, None, [o + "/m.npz"]),
        ("PLY: 10 MB of empty face lists", ["import", str(ply_dir), "-o", o + "/c.npz", "--rate", "60"], 2, None,
         [o + "/c.npz"]),
        ("synthesize a 1e6 s phone", [S, "--manifold", m, "--phones", "p 1e6 aa 0.1", "-o", o + "/t.csv"], 2,
         None, [o + "/t.csv"]),
        ("synthesize --tempo 1e-6", [S, "--manifold", m, "--text", "bob", "--tempo", "1e-6", "-o",
                                     o + "/t.csv"], 2, None, [o + "/t.csv"]),
        ("synthesize --inverse-dims 10", [S, "--manifold", m, "--phones", "p 0.1 aa 0.1", "--inverse-dims", "10",
                                          "-o", o + "/t.csv"], 2, None, [o + "/t.csv"]),
        ("a FIFO as input", ["info", str(fifo)], 2, None, []),
        ("session source /etc/passwd", ["@py", load.format(s_passwd)], 1, "refused:", []),
        ("session source ../../etc/passwd", ["@py", load.format(s_rel)], 1, "refused:", []),
        ("session source of the wrong type", ["@py", load.format(s_type)], 1, "refused:", []),
        ("session nested 100000 deep", ["@py", load.format(s_deep)], 1, "refused:", []),
        ("session frame out of range", ["@py", apply.format(s_range)], 1, "refused:", []),
        ("session source a FIFO", ["@py", load.format(s_fifo)], 1, "refused:", []),
        ("CSV time column + different --rate", ["import", str(csv), "-o", o + "/c.npz", "--rate", "60"], 2,
         "100 Hz", [o + "/c.npz"]),
        ("long table with frame gaps", ["import", str(gaps), "-o", o + "/g.npz", "--rate", "60"], 0, "7, 8", []),
        ("alignment 25x longer than the data", ["import", str(csv), "--alignment", str(lab25), "-o",
                                                o + "/a.npz"], 2, "25", [o + "/a.npz"]),
        ("npz phones outside the utterance", ["import", str(ph), "-o", o + "/p.npz"], 2, "phone", [o + "/p.npz"]),
        ("empty text", [S, "--manifold", m, "--text", "", "-o", o + "/t.csv"], 2, None, [o + "/t.csv"]),
        ("text of punctuation only", [S, "--manifold", m, "--text", "...", "-o", o + "/t.csv"], 2, None,
         [o + "/t.csv"]),
        ("'café' (unknown word)", [S, "--manifold", m, "--text", "café", "-o", o + "/t.csv"], 2, "'café'",
         [o + "/t.csv"]),
        ("info on a Haskins .mat", ["info", str(shared / "haskins-ieee" / "F01_B01_S01_R01_N.mat")], 2,
         "lipspace import", []),
        ("info on a MOCHA .ema", ["info", str(shared / "mocha-fsew0" / "fsew0_001.ema")], 2, "lipspace import", []),
        ("corpus name with escape codes", ["info", str(esc)], 0, "!ESC", []),
        ("cache keyed on the fitting code", ["@py", "from app.source_loading import cached_manifold_path as p; "
                                             "from engine.manifold import algorithm_fingerprint as a; "
                                             "assert a() in p('small').name; print('keyed')"], 0, None, []),
    ]


#: runs the case as a child and reports its peak resident memory (MiB x 1024) and exit status on stderr
_PEAK = ("import resource, signal, subprocess, sys\n"
         "signal.signal(signal.SIGTERM, lambda *a: None)  # the case gets it (a handler, not SIG_IGN: reset by exec)\n"
         "r = subprocess.run(sys.argv[1:])\n"
         "print('@@PEAK', resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, r.returncode, file=sys.stderr)")


def run_case(argv, cwd, cap, timeout, root):
    env = dict(os.environ, PYTHONPATH=str(root), LIPSPACE_CACHE_DIR=str(cwd / "cache"),
               LIPSPACE_STATE_DIR=str(cwd / "state"))
    env.pop("DISPLAY", None)
    sig = None
    if argv[-1].startswith("@SIGTERM"):
        sig, argv = float(argv[-1].split()[1]), argv[:-1]
    cmd = [sys.executable, "-c", argv[1]] if argv[0] == "@py" else [sys.executable, "-m", "app.cli", *argv]
    cmd = [sys.executable, "-c", _PEAK, *cmd]  # the case's own peak memory, not this script's children's

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

    t = time.perf_counter()
    p = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         preexec_fn=limit, start_new_session=True)
    try:
        if sig is not None:
            try:
                p.wait(sig)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGTERM)
        out, err = p.communicate(timeout=timeout)
        code = p.returncode
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)  # the case and its wrapper
        out, err = p.communicate()
        code = "hang"
    wall = time.perf_counter() - t
    peak = float("nan")
    if "@@PEAK " in err:
        err, _, tail = err.rpartition("@@PEAK ")
        peak = float(tail.split()[0]) / 1024
        if code not in ("hang",) and tail.split()[1:]:
            code = int(tail.split()[1])
    return code, wall, peak, out, err


def verdict(code, out, err, expect, says, must_not_exist, d):
    parts = list(d.rglob(".*.part*"))
    if code == "hang":
        return "HANG"
    if "Traceback" in err:
        return "TRACEBACK"
    if isinstance(code, int) and code < 0 or code in (137, 139, 134):
        return "CRASH"
    if expect == 2 and code == 0:
        return "SILENT"
    if parts or code != 0 and any(Path(f).exists() for f in must_not_exist):
        for p in parts:
            p.unlink()
        return "LEFT"
    if expect == 1:  # a python snippet that must print the refusal (and never a file's content)
        return "ok" if code == 0 and says in out and "root:" not in err + out else \
            "SILENT" if code == 0 else "MISREPORT"
    if expect is None:  # a signal: stopped with 128+15, or finished before it
        return "ok" if code in (0, 143) else "MISREPORT"
    if says == "!ESC":
        return "ok" if "\x1b" not in out + err else "SILENT"
    if says and says not in err:
        return "MISREPORT" if code == expect else "SILENT"
    if code != expect:
        return "MISREPORT"
    if code == 2 and not err.startswith("usage:") and err.strip().count("\n") > 0:
        return "MISREPORT"
    return "ok"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", default=str(ROOT), help="project tree to run (default: this one)")
    ap.add_argument("--cap-gb", type=float, default=3.0, help="address-space cap per process (GB)")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds before a case counts as a hang")
    ap.add_argument("--only", default=None, help="run the cases whose name contains this text")
    ap.add_argument("--json", default=None, help="write the rows here")
    args = ap.parse_args()
    root = Path(args.root).resolve()
    cap = int(args.cap_gb * 2**30)
    print(f"tree {root}; load average {os.getloadavg()[0]:.2f}; cap {args.cap_gb:g} GB address space; "
          f"timeout {args.timeout:g} s")
    rows = []
    with tempfile.TemporaryDirectory(prefix="lipspace-campaign-") as tmp:
        d = Path(tmp)
        r = subprocess.run([sys.executable, "-c", SETUP, str(d)], cwd=d, capture_output=True, text=True,
                           env=dict(os.environ, PYTHONPATH=str(root), LIPSPACE_CACHE_DIR=str(d / "cache")))
        if r.returncode:
            print(r.stderr[-2000:])
            return 1
        for name, argv, expect, says, gone in cases(d):
            if args.only and args.only not in name:
                continue
            (d / "out").mkdir(exist_ok=True)
            code, wall, peak, out, err = run_case(argv, d, cap, args.timeout, root)
            v = verdict(code, out, err, expect, says, gone, d)
            first = (err.strip().splitlines() or out.strip().splitlines() or [""])[-1 if "Traceback" in err else 0]
            rows.append({"case": name, "exit": code, "wall_s": round(wall, 2), "peak_mb": None if peak != peak else round(peak),
                         "verdict": v, "said": first[:160]})
            mem = "     - " if peak != peak else f"{peak:6.0f} MB"  # a case killed at the timeout reports none
            print(f"{v:10s} {str(code):>5s} {wall:6.1f} s {mem}  {name:42s} {first[:100]!r}", flush=True)
            for p in (d / "out").rglob("*"):
                if p.is_file():
                    p.unlink()
    counts = {}
    for row in rows:
        counts[row["verdict"]] = counts.get(row["verdict"], 0) + 1
    print("summary: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) + f" of {len(rows)} cases")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
