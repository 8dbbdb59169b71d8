"""The bad-input campaigns of issues 16, 30 and 45 as a checklist: every case the issues list,
and more of each class, run as a real ``lipspace`` process under a memory cap and a
timeout, one line per case, grouped by the class of issue 45 they test.

Usage: python benchmarks/campaign_bad_input.py [--root TREE] [--cap-gb 3] [--timeout 60] [--only TEXT]

``--root`` runs the cases against another checkout of the project (e.g. an older commit
extracted with ``git archive REV | tar -x -C DIR``) to compare before and after; the
manifold and corpus inputs are made by that tree's own code, the damaged recordings by
this script. Each line: the verdict, exit status, wall time, peak resident memory of the
case's process, the case and the first line it printed:

* ``ok``          exit as expected, one clean line, nothing left behind, the expected
                  refusal or warning said
* ``TRACEBACK``   a Python traceback reached the user
* ``CRASH``       killed by a signal (segfault, abort, OOM kill) or the memory cap
* ``HANG``        still running at the timeout (or alive after a stop signal)
* ``SILENT``      exit 0 where the input should have been refused, or repaired or
                  reinterpreted without saying so (and kept in the corpus history for ``info``)
* ``LOST``        a user file that existed before (or appeared while the command ran) was
                  changed or removed, or a run that lost an input exited 0 without ``--skip-bad``
* ``LEFT``        partial output: a failed or stopped command left a file (or ``.part`` file)
                  behind, or its message says nothing was written while something was
* ``MISREPORT``   misleading: refused, but without saying what the issue asks it to say, or
                  naming a temporary file, a Python identifier or an engine module
* ``n/a``         the case needs what this machine lacks (``unshare`` for a full disk, Xvfb,
                  the video extra)

Full and read-only disks are real: the case runs in a private mount namespace
(``unshare -rm``, no root needed) with a tiny or read-only tmpfs where it writes.

The cases live in ``_campaign_16_30.py`` (the first two campaigns) and ``_campaign_45.py``
(the third, grouped by its nine classes). A summary counts each verdict and gives the
tally of issue 45 (lost, crash, hang, traceback, partial, silent, misleading); ``--json``
writes the rows.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _campaign_16_30 import cases, cases_30  # noqa: E402
from _campaign_45 import cases_45  # noqa: E402
from _campaign_case import ROOT, Case, _old  # noqa: E402

#: issue 45's names for the verdicts it counts
TALLY = (("LOST", "lost"), ("CRASH", "crash"), ("HANG", "hang"), ("TRACEBACK", "traceback"), ("LEFT", "partial"),
         ("SILENT", "silent"), ("MISREPORT", "misleading"))

SETUP = r'''
import json, sys
import numpy as np
from engine.talker.synthetic import load_synthetic
from engine.manifold.model import Manifold
d = sys.argv[1]
c = load_synthetic(preset="small")
tiny = c.subset([u.id for u in c.utterances[:3]])
tiny.save(d + "/corpus.npz")
c.save(d + "/small.npz")
Manifold(n_states=20).fit(tiny).save(d + "/manifold.npz")
'''


#: runs the case as a child and reports its peak resident memory (MiB x 1024) and exit status on stderr
_PEAK = ("import resource, signal, subprocess, sys\n"
         "signal.signal(signal.SIGTERM, lambda *a: None)  # the case gets it (a handler, not SIG_IGN: reset by exec)\n"
         "r = subprocess.run(sys.argv[1:])\n"
         "print('@@PEAK', resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, r.returncode, file=sys.stderr)")


#: inside a private mount namespace: a tmpfs at $1 (options $2), the case, then how many files it left there
_MOUNTED = ('mkdir -p "$1" && mount -t tmpfs -o "$2" tmpfs "$1" || exit 97; shift 2; "$@"; rc=$?; '
            'echo "@@TINY $(find "$0" -type f | wc -l)" >&2; exit $rc')


def can_mount() -> bool:
    """Whether ``unshare -rm`` can mount a private tmpfs here (a real full or read-only disk)."""
    if shutil.which("unshare") is None:
        return False
    r = subprocess.run(["unshare", "-rm", "sh", "-c", "mount -t tmpfs -o size=64k tmpfs /mnt && echo ok"],
                       capture_output=True, text=True)
    return r.stdout.strip() == "ok"


def _command(case, cwd):
    """The process a case runs: ``lipspace ARGV``, a Python snippet (``@py``) or a shell script (``@sh``, with
    ``$PY`` the interpreter and ``$LIPSPACE`` the command)."""
    argv = list(case.argv)
    if argv[-1].startswith("@SIGTERM"):
        argv = argv[:-1]
    if argv[0] == "@py":
        return [sys.executable, "-c", argv[1]]
    if argv[0] == "@sh":
        return ["sh", "-c", argv[1]]
    return [sys.executable, "-m", "app.cli", *argv]


def run_case(case, cwd, cap, timeout, root):
    env = dict(os.environ, PYTHONPATH=str(root), LIPSPACE_CACHE_DIR=str(cwd / "cache"),
               LIPSPACE_STATE_DIR=str(cwd / "state"), LIPSPACE_CONFIG_DIR=str(cwd / "config"),
               PY=sys.executable, LIPSPACE=f"{sys.executable} -m app.cli")
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    env.update(case.env)
    sig = case.stop_after
    if case.argv[-1].startswith("@SIGTERM"):
        sig = float(case.argv[-1].split()[1])
    cmd = _command(case, cwd)
    if case.mount:
        tiny = str(cwd / "tiny")
        opts = "ro,size=64k" if case.mount == "ro" else f"size={case.mount.split(':')[1]}"
        cmd = ["unshare", "-rm", "sh", "-c", _MOUNTED, tiny, tiny, opts, *cmd]
    cmd = [sys.executable, "-c", _PEAK, *cmd]  # the case's own peak memory, not this script's children's
    timeout = case.timeout or timeout

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

    t = time.perf_counter()
    p = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         preexec_fn=limit, start_new_session=True)
    try:
        if sig is not None and case.stop_when or case.during is not None:
            # mid-way: once the command has begun writing what it writes (or after stop_after s)
            deadline = time.monotonic() + (sig if sig is not None else timeout)
            while p.poll() is None and time.monotonic() < deadline and not (
                    case.stop_when and any(cwd.glob(case.stop_when))):
                time.sleep(0.02)
            if p.poll() is None:
                if case.during is not None:
                    case.during(cwd)
                else:
                    os.killpg(p.pid, signal.SIGTERM)
        elif sig is not None:
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
    tiny_files = 0
    if "@@TINY " in err:
        err, _, tail = err.rpartition("@@TINY ")
        tiny_files = int(tail.split()[0])
    return code, wall, peak, out, err, tiny_files


#: what no message may show: a temporary file, a Python identifier or exception class, an engine module
_UNPLAIN = re.compile(r"\.part\b|\.part[-.]|\bengine\.\w|\w+\.py\b|\b[A-Z]\w+(Error|Exception)\b|"
                      r"\b(fill_gaps|rate|format|layout|variable|points|space|alignment|key_frames|n_states|scale|"
                      r"clear)=")


def _digest(p) -> str | None:
    p = Path(p)
    return hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else None


_WORDS = ("ok", "n/a", "HANG", "TRACEBACK", "CRASH", "LOST", "LEFT", "SILENT", "MISREPORT")


def _said_verdict(text):
    """The verdict a snippet printed (``@@VERDICT WORD``), or None."""
    m = re.search(r"@@VERDICT (\S+)", text)
    return m.group(1) if m and m.group(1) in _WORDS else None


def verdict(case, code, out, err, d, root, before, tiny_files=0):
    expect, says, must_not_exist = case.expect, case.says, case.gone
    parts = list(d.rglob(".*.part*"))
    if code == "hang":
        return "HANG"
    if "Traceback" in err + out:
        return "TRACEBACK"
    if code == 97:
        return "n/a"
    if isinstance(code, int) and code < 0 or code in (137, 139, 134):
        return "CRASH"
    own = _said_verdict(out)
    if own is not None and own != "ok":
        return own
    if any(_digest(k) != h for k, h in before.items()) and not (expect is None and code == 0):  # --force, done
        return "LOST"
    if expect == 2 and code == 0:
        return "LOST" if case.loses_input else "SILENT"
    if parts or code != 0 and any(Path(f).exists() for f in must_not_exist) or code != 0 and tiny_files:
        for p in parts:
            shutil.rmtree(p, ignore_errors=True) if p.is_dir() else p.unlink()
        return "LEFT"
    if "nothing was written" in err and (tiny_files or any(Path(f).exists() for f in must_not_exist)):
        return "LEFT"
    if case.never and case.never in err + out:
        return "MISREPORT"
    if _UNPLAIN.search(err):
        return "MISREPORT"
    if case.after is not None and (code == 0 or case.expect not in (0, 1)):
        problem = case.after(d, root)
        if problem:
            word = problem.split(":", 1)[0]
            return word if word in _WORDS else "SILENT"
    if expect == 1:  # a python snippet that must print the refusal (and never a file's content)
        return "ok" if code == 0 and says in out and "root:" not in err + out else \
            "SILENT" if code == 0 else "MISREPORT"
    if expect not in (None, 0, 2):  # a script's own exit status (130 after SIGINT, ...)
        if says and says not in err + out:
            return "MISREPORT"
        return "ok" if code == expect else "MISREPORT"
    if expect is None:  # a signal: stopped with 128+15, or finished before it
        return "ok" if code in (0, 143) else "MISREPORT"
    if says == "!ESC":
        return "ok" if "\x1b" not in out + err else "SILENT"
    if says and says not in err:  # a repair not said is silent; a refusal without its reason misreports
        return "SILENT" if code == 0 else "MISREPORT"
    if code != expect:
        return "MISREPORT"
    if code == 2 and not err.startswith("usage:") and err.strip().count("\n") >= case.lines:
        return "MISREPORT"
    return "ok"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", default=str(ROOT), help="project tree to run (default: this one)")
    ap.add_argument("--cap-gb", type=float, default=3.0, help="address-space cap per process (GB)")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds before a case counts as a hang")
    ap.add_argument("--only", default=None, help="run the cases whose name contains this text")
    ap.add_argument("--group", default=None, help="run the cases of the classes whose name starts with this (e.g. "
                                                  "'3', or '' for all of issue 45's)")
    ap.add_argument("--json", default=None, help="write the rows here")
    args = ap.parse_args()
    root = Path(args.root).resolve()
    cap = int(args.cap_gb * 2**30)
    mountable = can_mount()
    print(f"tree {root}; load average {os.getloadavg()[0]:.2f}; cap {args.cap_gb:g} GB address space; "
          f"timeout {args.timeout:g} s; full/read-only disks: "
          f"{'tmpfs in a private mount namespace' if mountable else 'n/a'}")
    rows = []
    with tempfile.TemporaryDirectory(prefix="lipspace-campaign-") as tmp:
        d = Path(tmp)
        r = subprocess.run([sys.executable, "-c", SETUP, str(d)], cwd=d, capture_output=True, text=True,
                           env=dict(os.environ, PYTHONPATH=str(root), LIPSPACE_CACHE_DIR=str(d / "cache")))
        if r.returncode:
            print(r.stderr[-2000:])
            return 1
        (d / "out").mkdir(exist_ok=True)
        sys.path.insert(0, str(ROOT))  # the damaged recordings are written with this tree's writers
        all_cases = [Case(*t) for t in cases(d)] + cases_30(d) + cases_45(d)
        group = None
        for case in all_cases:
            if args.only and args.only not in case.name or args.group is not None and not (
                    case.group and case.group.startswith(args.group)):
                continue
            if case.group != group:
                group = case.group
                print(f"--- {group or 'the checklist of issues 16 and 30'}", flush=True)
            if (d / "out").exists():
                shutil.rmtree(d / "out")
            (d / "out").mkdir()
            for k in case.keep:  # the user's own files, present before the run
                _old(*k) if isinstance(k, tuple) else _old(k)
            if case.prepare is not None:
                case.prepare(d)
            before = {str(k[0] if isinstance(k, tuple) else k): None for k in case.keep}
            before = {k: _digest(k) for k in before}
            if case.mount and not mountable:
                code, wall, peak, out, err, left = 97, 0.0, float("nan"), "", "", 0
            else:
                code, wall, peak, out, err, left = run_case(case, d, cap, args.timeout, root)
            v = verdict(case, code, out, err, d, root, before, left)
            first = (err.strip().splitlines() or out.strip().splitlines() or [""])[-1 if "Traceback" in err else 0]
            rows.append({"case": case.name, "group": case.group, "exit": code, "wall_s": round(wall, 2),
                         "peak_mb": None if peak != peak else round(peak), "verdict": v, "said": first[:160]})
            mem = "     - " if peak != peak else f"{peak:6.0f} MB"  # a case killed at the timeout reports none
            print(f"{v:10s} {str(code):>5s} {wall:6.1f} s {mem}  {case.name:42s} {first[:100]!r}", flush=True)
    counts = {}
    for row in rows:
        counts[row["verdict"]] = counts.get(row["verdict"], 0) + 1
    print("summary: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) + f" of {len(rows)} cases")
    print("tally: " + ", ".join(f"{counts.get(k, 0)} {word}" for k, word in TALLY) +
          f" ({counts.get('ok', 0)} ok, {counts.get('n/a', 0)} n/a)")
    for g in dict.fromkeys(r["group"] for r in rows if r["group"]):
        mine = [r for r in rows if r["group"] == g]
        bad = [r for r in mine if r["verdict"] not in ("ok", "n/a")]
        which = f" ({', '.join(sorted({r['verdict'] for r in bad}))})" if bad else ""
        print(f"  {g}: {len(mine) - len(bad)} of {len(mine)} held{which}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

