"""The third bad-input campaign (issue 45), grouped by its nine classes, plus the two signal and display
cases of issue 39 item 8. Every case is a reproduction the issue lists or another of the same class."""
from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
import time
from pathlib import Path

from _campaign_case import Case, _mview

__all__ = ["cases_45", "GROUPS"]

GROUPS = ("1 data lost", "2 security", "3 crash and hang at start-up", "4 tracebacks", "5 memory",
          "6 partial output", "7 silent reinterpretation", "8 misleading messages", "9 valid input refused")
G1, G2, G3, G4, G5, G6, G7, G8, G9 = GROUPS
S = "synthesize"
PHONES = "p 0.1 aa 0.1"
#: the size of the sparse files that must be refused before they are read (the issue's truncate -s 6G)
HUGE = 6 * 2**30
USER = b"the user's own file\n"

LONG_TG = '''File type = "ooTextFile"
Object class = "TextGrid"

xmin = {xmin}
xmax = 0.6
tiers? <exists>
size = {n}
item []:
{tiers}'''
TIER = '''    item [{k}]:
        class = "IntervalTier"
        name = "{name}"
        xmin = {xmin}
        xmax = 0.6
        intervals: size = 2
        intervals [1]:
            xmin = {xmin}
            xmax = 0.3
            text = {first}
        intervals [2]:
            xmin = 0.3
            xmax = 0.6
            text = "aa"
'''


def _textgrid(path, *, names=("phones",), xmin=0, first='"p"'):
    tiers = "".join(TIER.format(k=k + 1, name=n, xmin=xmin, first=first) for k, n in enumerate(names))
    path.write_text(LONG_TG.format(xmin=xmin, n=len(names), tiers=tiers))
    return str(path)


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def _wav(path, seconds=0.3, rate=16000):
    import numpy as np
    import scipy.io.wavfile

    scipy.io.wavfile.write(path, rate, (np.sin(np.arange(int(seconds * rate)) / 9) * 8000).astype(np.int16))
    return path


def _is(kind, path, why):
    """An ``after`` check: ``path`` is still a FIFO / a symbolic link (else the verdict ``why``)."""
    def check(d, root):
        p = Path(path)
        ok = p.is_symlink() if kind == "link" else p.exists() and stat.S_ISFIFO(os.lstat(p).st_mode)
        return None if ok else why
    return check


def _holds(path, data, why):
    def check(d, root):
        p = Path(path)
        return None if p.is_file() and p.read_bytes() == data else why
    return check


def _absent(path, why):
    return lambda d, root: why if Path(path).exists() else None


def _present(path, why):
    return lambda d, root: None if Path(path).exists() else why


def _labels(path, want, why):
    """An ``after`` check: the corpus file ``path`` holds the phone label ``want``."""
    def check(d, root):
        import numpy as np

        try:
            labels = [str(x) for x in np.load(path, allow_pickle=False)["corpus_phone_labels"]]
        except (OSError, KeyError, ValueError):
            return f"SILENT: {path} was not written"
        return None if want in labels else f"{why} (labels {labels[:6]})"
    return check


def _sparse(path, size=HUGE):
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as fh:
        fh.truncate(size)
    return str(path)


def _fifo(path):
    if path.exists() or path.is_symlink():
        path.unlink()
    os.mkfifo(path)
    return str(path)


def _changed(src, dst, **changes):
    import numpy as np

    a = dict(np.load(src, allow_pickle=False))
    a.update(changes)
    with open(dst, "wb") as fh:
        np.savez(fh, **a)
    return str(dst)


def _script(d, name, text):
    p = d / "scripts" / name
    p.parent.mkdir(exist_ok=True)
    p.write_text(text)
    return str(p)


#: wait until the virtual X server answers (exit 97, 'n/a', when it never does: this machine's fault)
WAIT_FOR_X = r'''
n=0
until xdotool getdisplaygeometry >/dev/null 2>&1; do  # the virtual X server answers (else: this machine's fault)
  n=$((n+1)); [ $n -gt 100 ] && exit 97
  sleep 0.2
done
'''

#: under a virtual X server: start the window, wait for the restore question (two windows named Lipspace), send
#: the signal $1, and report a process still alive 15 s later as a hang
RESTORE_SIGNAL = WAIT_FOR_X + r'''
$LIPSPACE explore "$M" > "$D/gui.out" 2> "$D/gui.err" &
pid=$!
n=0
while kill -0 $pid 2>/dev/null; do
  c=$(xdotool search --onlyvisible --name '^Lipspace$' 2>/dev/null | wc -l)
  [ "$c" -ge 2 ] && break
  n=$((n+1)); [ $n -gt 900 ] && break
  sleep 0.2
done
sleep 1
kill -$1 $pid 2>/dev/null
n=0
while kill -0 $pid 2>/dev/null && [ $n -lt 60 ]; do sleep 0.25; n=$((n+1)); done
if kill -0 $pid 2>/dev/null; then echo "@@VERDICT HANG"; kill -9 $pid; fi
wait $pid
rc=$?
cat "$D/gui.err" >&2
exit $rc
'''

#: under a virtual X server: 'explore --restore' past a damaged autosave, stopped once it was set aside
RESTORE_DAMAGED = WAIT_FOR_X + r'''
$LIPSPACE explore --restore > "$D/gui.out" 2> "$D/gui.err" &
pid=$!
n=0
while kill -0 $pid 2>/dev/null && [ ! -d "$LIPSPACE_STATE_DIR/autosave/damaged" ] && [ $n -lt 900 ]; do
  sleep 0.2; n=$((n+1))
done
sleep 2
kill -TERM $pid 2>/dev/null
wait $pid
rc=$?
cat "$D/gui.err" >&2
exit $rc
'''


def _gui(script, sig=""):
    return ("command -v xvfb-run >/dev/null && command -v xdotool >/dev/null || exit 97\n"
            # a display number of its own (concurrent 'xvfb-run -a' runs can pick the same one)
            f'exec xvfb-run -a -n $(( $$ % 400 + 200 )) -s "-screen 0 1280x800x24" sh "{script}" {sig}')


def _autosave(state, body, pid=None, started=None):
    """A dead (or the given) run's marker and its autosave ``body`` in the state folder ``state``."""
    def prepare(d):
        a = Path(state) / "autosave"
        if a.exists():
            import shutil

            shutil.rmtree(a)
        a.mkdir(parents=True)
        run = f"{pid or _dead_pid()}-5"
        (a / f"running-{run}.json").write_text(json.dumps({"pid": pid or int(run.split("-")[0]),
                                                            "started": started or time.time() - 60}))
        (a / f"autosave-{run}.lipspace.json").write_text(body if isinstance(body, str) else json.dumps(body))
    return prepare


def cases_45(d: Path):
    """Issue 45's classes (and issue 39 item 8): each a real process, most failing on the code before the fix."""
    import numpy as np

    o, m, c = d / "out", str(d / "manifold.npz"), str(d / "corpus.npz")
    r = d / "rec45"
    r.mkdir(exist_ok=True)
    arrays = dict(np.load(m, allow_pickle=False))
    uid = str(arrays["corpus_utt_ids"][0])
    lips = r / "lips.csv"
    lips.write_text("time,UL_x,UL_y,LL_x,LL_y\n" + "".join(f"{k / 100:.2f},{np.sin(k / 7):.4f},2,{k % 5},-3\n"
                                                            for k in range(60)))
    lab = r / "lips.lab"
    lab.write_text("0 0.3 p\n0.3 0.6 aa\n")
    tg_lab = b"0 0.1 p\n0.1 0.3 aa\n0.3 0.5 m\n"
    tg = _textgrid(r / "in.TextGrid")
    both = r / "both"
    both.mkdir(exist_ok=True)
    (both / "b.csv").write_text(lips.read_text())
    _textgrid(both / "b.TextGrid")
    (both / "b.lab").write_text("0 0.3 m\n0.3 0.6 iy\n")
    withwav = r / "withwav"
    withwav.mkdir(exist_ok=True)
    (withwav / "w.csv").write_text(lips.read_text())
    (withwav / "w.wav").write_text("this is a text file, not sound\n")
    realwav = r / "realwav"
    realwav.mkdir(exist_ok=True)
    (realwav / "v.csv").write_text(lips.read_text())
    _wav(realwav / "v.wav")

    # ---- the security case's manifold: stored audio paths leading out of its folder
    sec = d / "sec"
    (sec / "sub").mkdir(parents=True, exist_ok=True)
    (sec / "private").mkdir(exist_ok=True)
    (sec / "private" / "secret.wav").write_text("SECRET: the user's private notes\n")
    _wav(sec / "private" / "real.wav")
    (sec / "sub" / "notes.wav").write_text("not sound either\n")
    link = sec / "sub" / "in.wav"
    if not link.is_symlink():
        link.symlink_to("../private/real.wav")
    ids = [str(x) for x in arrays["corpus_utt_ids"]]
    stored = ["../private/secret.wav", "notes.wav", "in.wav"][:len(ids)] + [""] * max(0, len(ids) - 3)
    sm = _changed(m, sec / "sub" / "m.npz", corpus_utt_audio=np.array(stored),
                  corpus_utt_audio_abs=np.array([str(sec / "private" / "secret.wav")] + [""] * (len(ids) - 1)))
    absm = _changed(m, sec / "sub" / "abs.npz", corpus_utt_audio=np.array([str(sec / "private" / "secret.wav")] +
                                                                         [""] * (len(ids) - 1)),
                    corpus_utt_audio_abs=np.array([""] * len(ids)))

    # ---- damaged manifolds and corpora (classes 4 and 7)
    deep = "[" * 100_000 + "]" * 100_000
    axes = _changed(m, d / "axes.npz", corpus_axes=np.array("x=up,y=up,z=up"))
    nested = _changed(m, d / "nested.npz", manifold_params=np.array('{"n_states": ' + deep + "}"))
    nested2 = _changed(m, d / "nested2.npz", **{"states/__params__": np.array('{"n_states": ' + deep + "}")})
    timings = _changed(m, d / "timings.npz", manifold_timings=np.array(deep))
    cax = _changed(c, d / "caxes.npz", corpus_axes=np.array("x=up,y=up"))
    fy = arrays["Fy"]
    cplx = _changed(m, d / "complex.npz", Fy=fy.astype(np.complex64))  # complex, imaginary parts 0: was accepted
    names = np.load(c, allow_pickle=False)["corpus_point_names"].copy()
    names[1] = names[0]
    dupc = _changed(c, d / "dupnames.npz", corpus_point_names=names)

    # ---- MVIEW files
    sig = np.random.default_rng(45).normal(size=(60, 6))
    srate2 = r / "srate2.mat"
    _mview(srate2, sig, srate=np.array([[100.0, 200.0]]))
    srate_c = r / "sratec.mat"
    _mview(srate_c, sig, srate=np.complex128(100 + 5j))
    two = r / "two.mat"
    _mview(two, sig)
    import scipy.io

    m1 = scipy.io.loadmat(two)
    scipy.io.savemat(two, {"two": m1["two"], "other": m1["two"]})

    # ---- TextGrids
    ml = _textgrid(r / "ml.TextGrid", first='"p\nb"')  # a label over two lines (valid in Praat's long format)
    quote = _textgrid(r / "quote.TextGrid", first='"say ""hi"""')
    short = r / "short.TextGrid"
    short.write_text('File type = "ooTextFile short"\n"TextGrid"\n\n0\n0.6\n<exists>\n1\n"IntervalTier"\n"phones"\n0\n'
                     '0.6\n2\n0\n0.3\n"m\ne"\n0.3\n0.6\n"aa"\n')
    neg = _textgrid(r / "neg.TextGrid", xmin=-0.5)
    dup_tiers = _textgrid(r / "dup.TextGrid", names=("phones", "words", "phones"))

    # ---- window state files (class 3)
    st = d / "state45"
    st.mkdir(exist_ok=True)
    load = ("from app.files.session import load_session, SessionError\ntry:\n    d = load_session({!r})\n"
            "except SessionError as exc:\n    print('refused:', exc)\nelse:\n    print('@@VERDICT SILENT loaded')")
    sel = st / "sel.lipspace.json"
    sel.write_text(json.dumps({"lipspace_session": 2, "source": {"path": m}, "selection": [3]}))
    fifo_arrays = st / "fa.lipspace.json"
    fifo_arrays.write_text(json.dumps({"lipspace_session": 2, "source": {"path": None, "preset": "small"},
                                       "synthetic": {"label": "x", "rate": 60.0, "method": "linear", "warnings": []},
                                       "arrays": {"file": "fa.lipspace.npz", "sha256": "0" * 64}}))
    zero_arrays = st / "za.lipspace.json"
    zero_arrays.write_text(fifo_arrays.read_text().replace("fa.lipspace.npz", "za.lipspace.npz"))

    def arrays_prepare(d):
        _fifo(st / "fa.lipspace.npz")
        z = st / "za.lipspace.npz"
        if not z.is_symlink():
            z.symlink_to("/dev/zero")
        _fifo(st / "fifo.lipspace.json")

    restore = ("import pathlib\nfrom app.files.autosave import Autosaver, resolve_recovery\n"
               "from app.files.session import SessionError\na = Autosaver(pathlib.Path({!r}) / 'autosave')\n"
               "rec = a.begin()\nprint('offered' if rec else 'nothing offered')\ntry:\n"
               "    resolve_recovery(a, rec, restore=True)\nexcept SessionError as exc:\n    print('refused:', exc)\n"
               "a.finish()\nb = Autosaver(pathlib.Path({!r}) / 'autosave')\nprint('again:', b.begin(), b.set_aside)\n"
               "b.finish()")
    marker_fifo = ("import pathlib, os\nfrom app.files.autosave import Autosaver\nd = pathlib.Path({!r})\n"
                   "d.mkdir(parents=True, exist_ok=True)\np = d / 'running-4242-1.json'\n"
                   "os.path.exists(p) or os.mkfifo(p)\na = Autosaver(d)\nrec = a.begin()\n"
                   "print('refused:' if a.set_aside else '@@VERDICT SILENT', a.set_aside)\na.finish()")
    settings = ("import os, pathlib\nfrom app.window_settings import WindowSettings\n"
                "w = WindowSettings()\nprint('refused:' if w.set_aside else '@@VERDICT SILENT', w.set_aside)")
    pid1 = ("import pathlib\nfrom app.files.autosave import Autosaver\na = Autosaver(pathlib.Path({!r}) / 'autosave')\n"
            "rec = a.begin()\nprint('offered' if rec else '@@VERDICT SILENT never offered nor said', rec)\na.finish()")
    big_session = ("from app.files.session import load_session, SessionError\ntry:\n    load_session({!r})\n"
                   "except SessionError as exc:\n    print('refused:', exc)")

    # ---- partial output (class 6): SIGKILL while a command stages, then the same command again
    killed = ("import glob, os, signal, subprocess, sys, time\nargv = {argv!r}\nout = {out!r}\n"
              "p = subprocess.Popen([sys.executable, '-m', 'app.cli', *argv], stdout=subprocess.DEVNULL, "
              "stderr=subprocess.DEVNULL)\nt = time.monotonic() + 50\n"
              "while p.poll() is None and time.monotonic() < t and not glob.glob(os.path.join(out, {pat!r})):\n"
              "    time.sleep(0.005)\nhit = p.poll() is None\np.kill()\np.wait()\n"
              "r = subprocess.run([sys.executable, '-m', 'app.cli', *argv, '--force'], capture_output=True, "
              "text=True)\nleft = [q for q in os.listdir(out) if '.part' in q]\n"
              "print('killed while staging' if hit else 'finished first', r.returncode, r.stderr.strip()[:200])\n"
              "print('@@VERDICT LEFT' if left else 'ok: nothing left', left)")
    two_builds = ("import subprocess, sys\nout = {out!r}\nargv = [sys.executable, '-m', 'app.cli', 'build', {c!r}, "
                  "'-o', out, '-q']\nps = [subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, "
                  "text=True) for _ in range(2)]\nres = [p.communicate() for p in ps]\n"
                  "wrote = [o for o, e in res if 'wrote' in o]\n"
                  "refused = [e for o, e in res if 'appeared while' in e]\n"
                  "print('ok: one wrote, one refused' if len(wrote) == 1 and refused else "
                  "'@@VERDICT LOST both said wrote' if len(wrote) == 2 else 'unexpected', [e[-120:] for o, e in res])")

    # ---- a folder of videos with one damaged (class 9), when the video extra is installed
    vids = d / "vids"
    video_case = ["@sh", "exit 97"]
    try:
        import mediapipe  # noqa: F401
        import skimage.data

        from engine.io.video.synth import write_video  # noqa: F401

        vids.mkdir(exist_ok=True)
        from engine.io.video.synth import moving_image_frames

        img = np.ascontiguousarray(skimage.data.astronaut()[0:256, 96:352])
        write_video(vids / "a.mp4", moving_image_frames(img, np.tile([0.0, 1.0, 0.0, 0.0], (12, 1))), 30)
        (vids / "b.mp4").write_bytes((vids / "a.mp4").read_bytes()[:600])  # cut short: damaged
        video_case = ["import", str(vids), "-o", f"{o}/v.npz", "--skip-bad", "-q"]
    except Exception:  # noqa: BLE001 - no video extra: the case is n/a
        pass

    sigint = _script(d, "restore_signal.sh", RESTORE_SIGNAL)
    damaged = _script(d, "restore_damaged.sh", RESTORE_DAMAGED)
    gui_env = {"M": m, "D": str(d), "LIPSPACE_STATE_DIR": str(d / "st_gui"), "LIPSPACE_CONFIG_DIR": str(d / "cfg_gui")}
    imp = ["import"]
    return [
        # ------------------------------------------------------------ 1. data lost
        Case("--praat's table over -o (one file)", [S, "--manifold", m, "--textgrid", tg, "--praat", f"{o}/p.TextGrid",
                                                    "-o", f"{o}/p.csv", "--method", "linear", "-q"], 2,
             "written twice", [f"{o}/p.csv", f"{o}/p.TextGrid"], loses_input=True, group=G1),
        Case("evaluate --csv and --markdown one file", ["evaluate", c, "--csv", f"{o}/r.csv", "--markdown",
                                                        f"{o}/r.csv", "-q"], 2, "both name", [f"{o}/r.csv"],
             loses_input=True, group=G1),
        Case("--praat's table over its --textgrid input", [S, "--manifold", m, "--textgrid", f"{o}/t.csv", "--praat",
                                                           f"{o}/t.TextGrid", "--force", "--method", "linear", "-q"],
             2, "also an input", keep=[(o / "t.csv", tg_lab)], group=G1),
        # the user's file is written 4 s in (during the fit; on a very loaded machine before the command looked:
        # refused as existing then, equally safe; either way nothing was written)
        Case("a file written at -o while build runs", ["build", str(d / "small.npz"), "-o", f"{o}/m.npz", "-q"], 2,
             "nothing was written", stop_after=4.0, during=lambda d: (d / "out" / "m.npz").write_bytes(USER),
             after=_holds(o / "m.npz", USER, "LOST: the user's m.npz was replaced"), loses_input=True, group=G1),
        Case("two builds to one new -o", ["@py", two_builds.format(out=f"{o}/two.npz", c=c)], 1, "ok:", group=G1),
        Case("-o a FIFO with --force", [S, "--manifold", m, "--phones", PHONES, "-o", f"{o}/f.csv", "--force",
                                        "--method", "linear", "-q"], 2, "pipe", prepare=lambda d: _fifo(o / "f.csv"),
             after=_is("fifo", o / "f.csv", "LOST: the FIFO was replaced by a file"), loses_input=True, group=G1),
        Case("-o a link to a device with --force", [S, "--manifold", m, "--phones", PHONES, "-o", f"{o}/n.csv",
                                                    "--force", "--method", "linear", "-q"], 2, "device",
             prepare=lambda d: (o / "n.csv").symlink_to("/dev/null"),
             after=_is("link", o / "n.csv", "LOST: the link to the device was replaced"), loses_input=True, group=G1),
        Case("-o a dangling link, no --force", [S, "--manifold", m, "--phones", PHONES, "-o", f"{o}/dl.csv",
                                                "--method", "linear", "-q"], 2, "already exists",
             prepare=lambda d: (o / "dl.csv").symlink_to(o / "gone" / "x.csv"),
             after=_is("link", o / "dl.csv", "LOST: the link was replaced"), loses_input=True, group=G1),
        Case("import --quality-report over the user's file", imp + [str(lips), "-o", f"{o}/c.npz", "--quality-report",
                                                             f"{o}/qr.csv", "-q"], 2, "already exists",
             [f"{o}/c.npz"], keep=[(o / "qr.csv", USER)], group=G1),
        Case("cache --clear: the user's look-alikes", ["cache", "--clear"], 0, None,
             keep=[(d / "ucache" / "synthetic-default-notes.npz", USER), (d / "ucache" / "manifolds" /
                                                                           "synthetic-small-mine.npz", USER),
                   (d / "ucache" / "method-choice" / "0123456789abcdef-0123456789abcdef.json", b"{}")],
             env={"LIPSPACE_CACHE_DIR": str(d / "ucache")}, group=G1),
        Case("build's pruning: a user's older look-alike", ["build", "--preset", "small", "-o", f"{o}/s.npz", "-q"], 0,
             None, keep=[(d / "cache" / "synthetic-small-zz-mine.npz", USER)], timeout=300,
             prepare=lambda d: _old_mtime(d / "cache" / "synthetic-small-zz-mine.npz"), group=G1),
        # ------------------------------------------------------------ 2. security
        Case("stored audio ../private/secret.wav", [S, "--manifold", sm, "--utterance", ids[0], "-o", f"{o}/x.glb",
                                                    "--method", "linear", "-q"], 0, "outside the folder",
             after=_absent(o / "x.wav", "SILENT: the private file was copied beside the export"), group=G2),
        Case("stored audio: a text file named .wav", [S, "--manifold", sm, "--utterance", ids[1], "-o", f"{o}/x.glb",
                                                      "--method", "linear", "-q"], 0, "not a WAV",
             after=_absent(o / "x.wav", "SILENT: a text file was copied as audio"), group=G2),
        Case("stored audio: a link out of the folder", [S, "--manifold", sm, "--utterance", ids[2], "-o",
                                                        f"{o}/x.glb", "--method", "linear", "-q"], 0,
             "outside the folder", after=_absent(o / "x.wav", "SILENT: the file behind the link was copied"),
             group=G2),
        Case("stored audio: an absolute path elsewhere", [S, "--manifold", absm, "--utterance", ids[0], "-o",
                                                          f"{o}/x.glb", "--method", "linear", "-q"], 0,
             "outside the folder", after=_absent(o / "x.wav", "SILENT: the private file was copied"), group=G2),
        # ------------------------------------------------------------ 3. crash and hang at start-up (+ issue 39 item 8)
        Case("autosave 'selection': 'x', restored", ["@py", restore.format(str(d / "st_sel"), str(d / "st_sel"))],
             1, "refused:", prepare=_autosave(d / "st_sel", {"lipspace_session": 2, "source": {"path": m},
                                                               "selection": "x"}), group=G3),
        Case("session 'selection': [3]", ["@py", load.format(str(sel))], 1, "refused:", group=G3),
        Case("session arrays file a FIFO", ["@py", load.format(str(fifo_arrays))], 1, "refused:",
             prepare=arrays_prepare, timeout=30, group=G3),
        Case("session arrays file a link to /dev/zero", ["@py", load.format(str(zero_arrays))], 1, "refused:",
             prepare=arrays_prepare, timeout=30, group=G3),
        Case("session file a FIFO", ["@py", load.format(str(st / "fifo.lipspace.json"))], 1, "refused:",
             prepare=arrays_prepare, timeout=30, group=G3),
        Case("autosave marker a FIFO", ["@py", marker_fifo.format(str(d / "st_fifo"))], 1, "refused:", timeout=30,
             group=G3),
        Case("settings file a FIFO", ["@py", settings], 1, "refused:", timeout=30,
             env={"LIPSPACE_CONFIG_DIR": str(d / "cfg_fifo")}, prepare=lambda d: (
                 (d / "cfg_fifo").mkdir(exist_ok=True), _fifo(d / "cfg_fifo" / "lipspace.ini")), group=G3),
        Case("DISPLAY names no X server", ["explore", m], 2, "no X server", env={"DISPLAY": ":57"}, group=G3),
        Case("WAYLAND_DISPLAY with no compositor", ["explore", m], 2, "no compositor",
             env={"WAYLAND_DISPLAY": "wayland-57", "XDG_RUNTIME_DIR": str(d)}, group=G3),
        Case("explore --restore past a damaged autosave", ["@sh", _gui(damaged)], 143, "could not be restored",
             env=gui_env, timeout=240, prepare=_autosave(d / "st_gui", {"lipspace_session": 2, "source": {"path": m},
                                                                        "selection": "x"}), group=G3),
        Case("SIGINT while the restore question is open", ["@sh", _gui(sigint, "INT")], 130, "stopped by SIGINT",
             env=gui_env, timeout=240, prepare=_autosave(d / "st_gui", {"lipspace_session": 2,
                                                                        "source": {"path": m}}), group=G3),
        Case("SIGTERM while the restore question is open", ["@sh", _gui(sigint, "TERM")], 143, "stopped by SIGTERM",
             env=gui_env, timeout=240, prepare=_autosave(d / "st_gui", {"lipspace_session": 2,
                                                                        "source": {"path": m}}), group=G3),
        # ------------------------------------------------------------ 4. tracebacks
        Case("info: stored axes x=up,y=up,z=up", ["info", axes], 2, "axes", group=G4),
        Case("info: parameters nested 100,000 deep", ["info", nested], 2, "nested too deeply", group=G4),
        Case("info: an estimator's parameters nested deep", ["info", nested2], 2, "nested too deeply", group=G4),
        Case("info: timings nested deep", ["info", timings], 2, "nested too deeply", group=G4),
        Case("info: a corpus's axes damaged", ["info", cax], 2, "axes", group=G4),
        Case("info m.npz >&- (stdout closed)", ["@sh", f'$LIPSPACE info "{m}" >&-; echo "exit $?"'], 1, "exit 1",
             group=G4),
        Case("synthesize -o t.csv >&-", ["@sh", f'$LIPSPACE {S} --manifold "{m}" --phones "{PHONES}" -o "{o}/t.csv" '
                                                f'--method linear -q >&-; echo "exit $?"'], 1, "exit 0",
             after=_present(o / "t.csv", "LOST: nothing written"), group=G4),
        # ------------------------------------------------------------ 5. memory
        Case("import a 6 GB CSV", imp + [str(d / "big" / "big.csv"), "-o", f"{o}/c.npz"], 2, "big.csv: ",
             [f"{o}/c.npz"], prepare=lambda d: _sparse(d / "big" / "big.csv"), never="Import fewer files", group=G5),
        Case("import --alignment a 6 GB TextGrid", imp + [str(lips), "--alignment", str(d / "big" / "big.TextGrid"),
                                                          "-o", f"{o}/c.npz"], 2, "big.TextGrid: ", [f"{o}/c.npz"],
             prepare=lambda d: _sparse(d / "big" / "big.TextGrid"), group=G5),
        Case("import a 6 GB .ema", imp + [str(d / "big" / "big.ema"), "-o", f"{o}/c.npz"], 2, "big.ema: ",
             [f"{o}/c.npz"], prepare=lambda d: _sparse(d / "big" / "big.ema"), never="Import fewer files", group=G5),
        Case("synthesize --textgrid a 6 GB TextGrid", [S, "--manifold", m, "--textgrid", str(d / "big" / "s.TextGrid"),
                                                       "-o", f"{o}/t.csv", "-q"], 2, "s.TextGrid: ", [f"{o}/t.csv"],
             prepare=lambda d: _sparse(d / "big" / "s.TextGrid"), group=G5),
        Case("a 6 GB session file", ["@py", big_session.format(str(d / "big" / "s.lipspace.json"))], 1, "refused:",
             prepare=lambda d: _sparse(d / "big" / "s.lipspace.json"), group=G5),
        Case("a 6 GB settings file", ["@py", settings], 1, "refused:",
             env={"LIPSPACE_CONFIG_DIR": str(d / "big" / "cfg")},
             prepare=lambda d: _sparse(d / "big" / "cfg" / "lipspace.ini"), group=G5),
        # ------------------------------------------------------------ 6. partial output
        Case("SIGKILL while table stages, then table", ["@py", killed.format(
            argv=["table", m, "--textgrid", f"{o}/tg", "-o", f"{o}/t.csv"], out=str(o), pat=".tg.part-*")], 1,
             "ok:", group=G6),
        Case("SIGKILL while synthesize writes, then again", ["@py", killed.format(
            argv=[S, "--manifold", m, "--phones", "sil 3 aa 3", "-o", f"{o}/t.csv", "--mesh-dir", f"{o}/mesh",
                  "--method", "linear", "-q"], out=str(o), pat=".mesh.part-*")], 1, "ok:", group=G6),
        Case("SIGKILL while build saves, then build", ["@py", killed.format(
            argv=["build", str(d / "small.npz"), "-o", f"{o}/m.npz", "-q"], out=str(o), pat=".*part*")], 1, "ok:",
             timeout=180, group=G6),
        # ------------------------------------------------------------ 7. silent reinterpretation
        Case("--manifold ''", [S, "--manifold", "", "--phones", PHONES, "-o", f"{o}/t.csv", "-q"], 2, "--manifold",
             [f"{o}/t.csv"], group=G7),
        Case("-o ''", [S, "--manifold", m, "--phones", PHONES, "-o", "", "-q"], 2, "-o", group=G7),
        Case("--mesh-dir ''", [S, "--manifold", m, "--phones", PHONES, "--mesh-dir", "", "-q"], 2, "--mesh-dir",
             group=G7),
        Case("clusters --phones ''", ["clusters", m, "--phones", ""], 2, "--phones", group=G7),
        Case("import --points UL,UL", imp + [str(lips), "-o", f"{o}/c.npz", "--points", "UL,UL"], 2, "twice",
             [f"{o}/c.npz"], group=G7),
        Case("a tier starting before 0 s", imp + [str(lips), "--alignment", neg, "-o", f"{o}/c.npz"], 2,
             "before the recording starts", [f"{o}/c.npz"], group=G7),
        Case("two tiers named 'phones'", imp + [str(lips), "--alignment", dup_tiers, "-o", f"{o}/c.npz"], 2,
             "both named", [f"{o}/c.npz"], group=G7),
        Case(".TextGrid and .lab both beside the input", imp + [str(both / "b.csv"), "-o", f"{o}/c.npz"], 0,
             "are beside it", group=G7),
        Case("a text file as rec.wav beside the input", imp + [str(withwav / "w.csv"), "-o", f"{o}/c.npz"], 0,
             "not linked", group=G7),
        Case("a WAV beside the input is linked and said", imp + [str(realwav / "v.csv"), "-o", f"{o}/c.npz"], 0,
             "audio v.wav linked", group=G7),
        Case("MVIEW SRATE [100 200]", imp + [str(srate2), "-o", f"{o}/c.npz", "--points", "UL,LL"], 2, "SRATE",
             [f"{o}/c.npz"], group=G7),
        Case("MVIEW SRATE 100+5i", imp + [str(srate_c), "-o", f"{o}/c.npz", "--points", "UL,LL"], 2, "SRATE",
             [f"{o}/c.npz"], group=G7),
        Case(".mat holding two MVIEW structs", imp + [str(two), "-o", f"{o}/c.npz", "--points", "UL,LL"], 2,
             "2 MVIEW struct arrays", [f"{o}/c.npz"], group=G7),
        Case("a complex-valued embedding", ["info", cplx], 2, "expected float", group=G7),
        Case("duplicated point names", ["info", dupc], 2, "both named", group=G7),
        Case("an autosave marker naming pid 1", ["@py", pid1.format(str(d / "st_pid1"))], 1, "offered",
             prepare=_autosave(d / "st_pid1", {"lipspace_session": 2, "source": {"path": m}}, pid=1,
                               started=time.time() - 30), group=G7),
        Case("evaluate --test-ids a,a", ["evaluate", c, "--test-ids", f"{uid},{uid}", "-q"], 2, "twice", group=G7),
        Case("--key-frames 0,,5", [S, "--manifold", m, "--utterance", uid, "--key-frames", "0,,5", "-q"], 2,
             "--key-frames", group=G7),
        Case("import --speaker ''", imp + [str(lips), "-o", f"{o}/c.npz", "--speaker", ""], 2, "--speaker",
             [f"{o}/c.npz"], group=G7),
        # ------------------------------------------------------------ 8. misleading messages
        Case("build --states 0", ["build", c, "-o", f"{o}/m.npz", "--states", "0", "-q"], 2, "--states",
             never="None for the default", group=G8),
        Case("build --embedding-dims 100000", ["build", c, "-o", f"{o}/m.npz", "--embedding-dims", "100000", "-q"], 2,
             "--embedding-dims", never="too few", group=G8),
        Case("build --seed -1", ["build", c, "-o", f"{o}/m.npz", "--seed", "-1", "-q"], 2, "--seed", group=G8),
        Case("build --seed 2**70", ["build", c, "-o", f"{o}/m.npz", "--seed", str(2**70), "-q"], 2, "--seed",
             never="random_state", group=G8),
        Case("build --variance 0", ["build", c, "-o", f"{o}/m.npz", "--variance", "0", "-q"], 2, "--variance",
             group=G8),
        Case("build --neighbors 2", ["build", c, "-o", f"{o}/m.npz", "--neighbors", "2", "-q"], 2, "--neighbors",
             never="n_neighbors", group=G8),
        Case("import --quality-max-gap -1", imp + [str(lips), "-o", f"{o}/c.npz", "--quality-max-gap", "-1"], 2,
             "--quality-max-gap", [f"{o}/c.npz"], never="-0.001 s", group=G8),
        Case("evaluate --states 0", ["evaluate", c, "--states", "0", "-q"], 2, "--states", group=G8),
        Case("import --points ''", imp + [str(lips), "-o", f"{o}/c.npz", "--points", ""], 2, "--points",
             never="concatenate", group=G8),
        Case("lipspace nosuchcommand", ["nosuchcommand"], 2, "unknown command", never="display", group=G8),
        Case("lipspace biuld", ["biuld", c], 2, "did you mean 'build'", never="display", group=G8),
        Case("synthesize --candidates 1e3", [S, "--manifold", m, "--phones", PHONES, "--candidates", "1e3"], 2,
             "--candidates", group=G8),
        Case("build ... > /dev/full", ["@sh", f'$LIPSPACE build "{c}" -o "{o}/m.npz" -q > /dev/full; echo "exit $?"'],
             1, "exit 0", after=_present(o / "m.npz", "LOST: the finished manifold was thrown away"), group=G8),
        Case("import ... 2>&-", ["@sh", f'$LIPSPACE import "{lips}" -o "{o}/c.npz" 2>&-; echo "exit $?"'], 1,
             "exit 0", group=G8),
        Case("explore a missing file with no X server", ["explore", f"{o}/missing.npz"], 2, "no such file",
             env={"DISPLAY": ":57"}, never="X server", group=G8),
        # ------------------------------------------------------------ 9. valid input refused
        Case("import vids/ --skip-bad, one video damaged", video_case, 0, "skipped (--skip-bad)", timeout=300,
             group=G9),
        Case("a label over two lines (long TextGrid)", imp + [str(lips), "--alignment", ml, "-o", f"{o}/c.npz"], 0,
             None, after=_labels(o / "c.npz", "p b", "SILENT: the two-line label was not kept"), group=G9),
        Case("a label over two lines (short TextGrid)", imp + [str(lips), "--alignment", str(short), "-o",
                                                              f"{o}/c.npz"], 0, None,
             after=_labels(o / "c.npz", "m e", "SILENT: the two-line label was not kept"), group=G9),
        Case("a label holding a double quote", imp + [str(lips), "--alignment", quote, "-o", f"{o}/c.npz"], 0, None,
             after=_labels(o / "c.npz", 'say "hi"', "SILENT: the label was misread"), group=G9),
    ]


def _old_mtime(p, age=3600.0):
    """Make ``p`` (a user's file) an hour old, older than the cache's entries."""
    t = time.time() - age
    os.utime(p, (t, t))
