"""The cases of the first two bad-input campaigns (issues 16 and 30), as a checklist."""
from __future__ import annotations

import json
import math
import os
import zlib
from pathlib import Path

from _campaign_case import ROOT, Case, _changed_npz, _info_says, _mview, _old, _pos

__all__ = ["cases", "cases_30"]


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
    times = np.load(c, allow_pickle=False)["corpus_phone_times"]
    ph = _changed_npz(c, d / "phones-out.npz", corpus_phone_times=times + 1000.0)
    esc = _changed_npz(c, d / "escape.npz", corpus_name=np.array("\x1b[31mRED\x1b]0;owned\x07"))
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
    load = ("from app.files.session import load_session, SessionError\ntry:\n    d = load_session({!r})\n"
            "except SessionError as exc:\n    print('refused:', exc)\nelse:\n    print('loaded', d['source'])")
    apply = ("from app.files.session import load_session, apply_session, SessionError\n"
             "from app.models.state import AppState\n"
             "from engine.manifold.model import Manifold\nd = load_session({!r})\n"
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
        ("cache keyed on the fitting code", ["@py", "from app.files.source_loading import cached_manifold_path as p; "
                                             "from engine.manifold.model import algorithm_fingerprint as a; "
                                             "assert a() in p('small').name; print('keyed')"], 0, None, []),
    ]




def cases_30(d: Path):
    """Issue 30's classes: data defects repaired and said or refused, no overwritten file, lost inputs,
    stops and failures at any moment, damaged window state files, messages that mislead."""
    import warnings

    import c3d
    import numpy as np

    rng = np.random.default_rng(30)
    o, m, c = d / "out", str(d / "manifold.npz"), str(d / "corpus.npz")
    r = d / "rec"
    r.mkdir(exist_ok=True)
    S = "synthesize"
    haskins = ROOT.parent / "shared" / "data" / "haskins-ieee" / "F01_B01_S01_R01_N.mat"

    # ---- recordings with the defects of item 1
    rows = ["time,UL_x,UL_y,LL_x,LL_y"]
    for k in range(60):
        v = [f"{math.sin(k / 5):.4f}", "2", "3", "4"]
        v[0] = "" if k in (10, 11) else v[0]
        v[1] = "nan" if k == 20 else v[1]
        v[2] = "inf" if k == 30 else v[2]
        rows.append(",".join([f"{k / 100:.2f}", *v]))
    holes = r / "holes.csv"
    holes.write_text("\n".join(rows) + "\n")
    dup = r / "dup.csv"
    dup.write_text("time,UL_x,UL_y,UL_x,LL_y\n" + "".join(f"{k / 100},1,2,3,4\n" for k in range(30)))
    nolx = r / "nolx.csv"
    nolx.write_text("time,UL_x,UL_y,LL_y\n" + "".join(f"{k / 100},1,2,4\n" for k in range(30)))
    huge_cell = r / "huge.csv"
    huge_cell.write_text("time,a_x,a_y\n" + "".join(f"{k / 100},{1e12 if k == 7 else k},0\n" for k in range(30)))
    from engine.io import write_est_track

    valid = np.ones(100, bool)
    valid[40:43] = False
    ema = write_est_track(r / "breaks.ema", np.arange(100) / 500, rng.normal(size=(100, 4)) * 100,
                          ["ul_x", "ul_y", "ll_x", "ll_y"], valid=valid)
    w = c3d.Writer(point_rate=120.0)
    w.set_point_labels(["UL", "LL"])
    for i in range(40):
        pts = np.zeros((2, 5), np.float32)
        pts[:, :3] = rng.normal(size=(2, 3))
        pts[1, 3] = -1 if i in (5, 6) else 0
        w.add_frames([(pts, np.zeros((0, 0)))])
    c3dp = r / "invalid.c3d"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with open(c3dp, "wb") as fh:
            w.write(fh)
    sig = rng.normal(size=(60, 6))
    sig[[3, 4], 0] = np.nan
    mat_nan = _mview(r / "hnan.mat", sig)
    mat_rate = _mview(r / "hrate.mat", rng.normal(size=(60, 6)), srate=1e300)
    mat_inf = _mview(r / "hinf.mat", rng.normal(size=(60, 6)), audio=np.full((4410, 1), np.inf))
    M = rng.normal(size=(100, 14))
    M[:60] = np.nan
    pos60 = _pos(r / "nan60.pos", M)
    pos = {v: _pos(r / f"rate-{k}.pos", rng.normal(size=(100, 14)), rate=v)
           for k, v in enumerate(("0", "1e300", "NaN", "abc"))}
    wave = r / "w.tsv"
    wave.write_text("Time\tSensor 1 Id\tSensor 1 Status\tSensor 1 Tx\tSensor 1 Ty\tSensor 1 Tz\n" + "".join(
        f"{k / 100:.2f}\t1\t{'Missing' if k == 7 else 'OK'}\t{k}\t1\t2\n" for k in range(40)))
    tg = r / "size2.TextGrid"
    lines = ['File type = "ooTextFile"', 'Object class = "TextGrid"', "", "xmin = 0", "xmax = 0.6",
             "tiers? <exists>", "size = 1", "item []:", "    item [1]:", '        class = "IntervalTier"',
             '        name = "phones"', "        xmin = 0", "        xmax = 0.6", "        intervals: size = 2"]
    for k in range(5):
        lines += [f"        intervals [{k + 1}]:", f"            xmin = {k * 0.12:g}",
                  f"            xmax = {(k + 1) * 0.12:g}", f'            text = "p{k}"']
    tg.write_text("\n".join(lines) + "\n")
    plyd = r / "ply"
    plyd.mkdir(exist_ok=True)
    from engine.io import write_ply

    for k in range(3):
        p = write_ply(plyd / f"f{k}.ply", np.eye(3) + k, [[0, 1, 2]])
        p.write_bytes(p.read_bytes() + (b"0 0 1\n" if k == 1 else b""))
    one = d / "one-frame.npz"
    from engine.recordings.corpus import Corpus, Utterance

    Corpus(frames=rng.normal(size=(40, 6)), rate=60, utterances=[Utterance(f"u{k}", k, k + 1) for k in range(40)],
           name="one-frame").save(one)
    frames = np.load(c, allow_pickle=False)["corpus_frames"].copy()
    frames[10, 3] = 1e30
    hugec = _changed_npz(c, d / "huge-coord.npz", corpus_frames=frames)
    accentc = _changed_npz(c, d / "accent.npz", corpus_name=np.array("café – ü"))
    many = d / "many"
    many.mkdir(exist_ok=True)
    for k in range(24):
        q = many / f"F01_R{k:02d}.mat"
        if haskins.is_file() and not q.exists():
            os.symlink(haskins, q)
    three = [str(ema), str(r / "notema.ema"), str(write_est_track(r / "b2.ema", np.arange(80) / 500,
                                                                     rng.normal(size=(80, 4)) * 100,
                                                                     ["ul_x", "ul_y", "ll_x", "ll_y"]))]
    (r / "notema.ema").write_text("this is not an EST track\n")
    uid = None
    try:
        from engine.manifold.model import Manifold

        uid = Manifold.load(m).corpus_.utterances[0].id
    except Exception:  # another tree's manifold format: the key-frame case names an unknown id then
        uid = "s0001"

    # ---- window state files (item 5), through their loaders (the window opens in tests/app)
    state = d / "state30"
    marker = ("import json, pathlib, sys\nfrom app.files.autosave import Autosaver\nd = pathlib.Path({!r})\n"
              "d.mkdir(parents=True, exist_ok=True)\n(d / 'running-4242-1.json').write_text({!r})\n"
              "(d / 'autosave-4242-1.lipspace.json').write_text('{{}}')\na = Autosaver(d)\nrec = a.begin()\n"
              "print('refused:', getattr(a, 'set_aside', None), rec)\na.finish()")
    session = ("from app.files.session import load_session, SessionError\nimport pathlib\np = pathlib.Path({!r})\n"
               "p.write_text({!r})\ntry:\n    d = load_session(p)\nexcept SessionError as exc:\n"
               "    print('refused:', exc)\nelse:\n    print('loaded', d.get('extra'), d.get('cameras'))")
    settings = ("import pathlib\nfrom PySide6 import QtCore\nfrom app.window_settings import WindowSettings\n"
                "p = pathlib.Path({!r})\np.parent.mkdir(parents=True, exist_ok=True)\np.write_text({!r})\n"
                "w = WindowSettings(QtCore.QSettings(str(p), QtCore.QSettings.Format.IniFormat))\n"
                "w.recent_files(); w.restore_layout\n"
                "print('refused:' if getattr(w, 'set_aside', None) else 'accepted', getattr(w, 'set_aside', None))")
    s_json = '{{"lipspace_session": 2, "source": {{"path": null, "preset": "small"}}, {}}}'

    imp = ["import"]
    return [
        # 1. data defects: repaired and said (and kept for info), or refused naming file, field, frame
        Case("CSV NaN, Inf and empty cells", imp + [str(holes), "-o", f"{o}/c.npz"], 0, "missing samples",
             after=_info_says(f"{o}/c.npz", "3 empty or NaN, 1 infinite")),
        Case("CSV cell of 1e12 (implausible)", imp + [str(huge_cell), "-o", f"{o}/c.npz"], 0, "implausibly large"),
        Case("EMA break flags", imp + [str(ema), "-o", f"{o}/c.npz", "--points", "UL,LL"], 0, "break flag 0",
             after=_info_says(f"{o}/c.npz", "frames 40-42")),
        Case("C3D invalid markers", imp + [str(c3dp), "-o", f"{o}/c.npz"], 0, "marked invalid"),
        Case("NaN in a Haskins signal", imp + [mat_nan, "-o", f"{o}/c.npz", "--points", "UL,LL"], 0, "4 NaN"),
        Case("NDI Wave status not OK", imp + [str(wave), "-o", f"{o}/c.npz", "--format", "wave"], 0,
             "status not OK"),
        Case(".pos 60 % NaN", imp + [pos60, "-o", f"{o}/c.npz"], 2, "60 of 100 frames", [f"{o}/c.npz"]),
        *[Case(f".pos SamplingFrequencyHz={v}", imp + [p, "-o", f"{o}/c.npz"], 2, "SamplingFrequencyHz",
               [f"{o}/c.npz"]) for v, p in pos.items()],
        Case("MVIEW SRATE 1e300", imp + [mat_rate, "-o", f"{o}/c.npz", "--points", "UL,LL"], 2, "SRATE is 1e+300",
             [f"{o}/c.npz"]),
        Case("CSV UL_x twice, no LL_x", imp + [str(dup), "-o", f"{o}/c.npz"], 2, "name the same coordinate",
             [f"{o}/c.npz"]),
        Case("CSV LL_y without LL_x", imp + [str(nolx), "-o", f"{o}/c.npz"], 2, "no LL_x column", [f"{o}/c.npz"]),
        Case("TextGrid size = 2 before 5 intervals", imp + [str(holes), "--alignment", str(tg), "-o", f"{o}/c.npz"],
             2, "count", [f"{o}/c.npz"]),
        Case("PLY with more rows than its header", imp + [str(plyd), "--rate", "30", "-o", f"{o}/c.npz"], 2,
             "follow the rows", [f"{o}/c.npz"]),
        Case("all-Inf audio channel", imp + [mat_inf, "-o", f"{o}/c.npz", "--audio-dir", f"{o}/aud", "--points",
                                             "UL,LL"], 2,
             "no finite sample", [f"{o}/c.npz", f"{o}/aud/hinf.wav"]),
        Case("--no-fill with a dropout", imp + [str(ema), "-o", f"{o}/c.npz", "--no-fill", "--points", "UL,LL"],
             2, "--no-fill", [f"{o}/c.npz"], never="fill_gaps"),
        Case("import --rate 0", imp + [str(plyd), "--rate", "0", "-o", f"{o}/c.npz"], 2, "--rate", [f"{o}/c.npz"]),
        # 2. no existing user file overwritten without --force; the refusal names it
        Case("--audio-dir over a user's WAV", imp + [str(haskins), "-o", f"{o}/h.npz", "--audio-dir", f"{o}/aud"], 2,
             "F01_B01_S01_R01_N.wav", [f"{o}/h.npz"],
             keep=[_old(o / "aud" / "F01_B01_S01_R01_N.wav")]),
        Case("--mesh-dir over frame files", [S, "--manifold", m, "--phones", "p 0.1 aa 0.1", "--mesh-dir",
                                             f"{o}/mesh"], 2, "frame_00000.obj", keep=[_old(o / "mesh" /
                                                                                          "frame_00000.obj")]),
        Case("figures over a figure", ["figures", m, "-o", f"{o}/figs", "--only", "scree", "-q"], 2, "scree.png",
             keep=[_old(o / "figs" / "scree.png")]),
        Case("clusters --csv over a table", ["clusters", m, "--csv", f"{o}/t.csv", "-q"], 2, "t.csv",
             keep=[_old(o / "t.csv")]),
        Case("synthesize -o over a trajectory", [S, "--manifold", m, "--phones", "p 0.1 aa 0.1", "-o", f"{o}/t.csv"],
             2, "t.csv", keep=[_old(o / "t.csv")]),
        Case("build -o over a manifold", ["build", c, "-o", f"{o}/m.npz", "-q"], 2, "m.npz",
             keep=[_old(o / "m.npz")]),
        Case("render -o over a video", ["render", "--manifold", m, "--phones", "p 0.1 aa 0.1", "-o", f"{o}/v.mp4"],
             2, "v.mp4", keep=[_old(o / "v.mp4")]),
        Case("evaluate --markdown over a report", ["evaluate", c, "--markdown", f"{o}/r.md", "-q"], 2, "r.md",
             keep=[_old(o / "r.md")]),
        Case(".glb over the WAV beside it", [S, "--manifold", m, "--phones", "p 0.1 aa 0.1", "-o", f"{o}/a.glb",
                                             "--audio", str(ROOT.parent / "shared" / "data" / "mocha-fsew0" /
                                                            "fsew0_001.wav")], 2, "a.wav", [f"{o}/a.glb"],
             keep=[_old(o / "a.wav")]),
        Case("--force replaces", [S, "--manifold", m, "--phones", "p 0.1 aa 0.1", "-o", f"{o}/t.csv", "--force"], 0,
             None, after=lambda d, root: None if (d / "out" / "t.csv").read_bytes().startswith(b"time,")
             else "--force did not replace t.csv"),
        # 3. a run that loses an input exits non-zero unless --skip-bad, which says how many
        Case("one unreadable input of three", imp + three + ["-o", f"{o}/c.npz", "--points", "UL,LL", "-q"], 2,
             "--skip-bad", [f"{o}/c.npz"], lines=2, loses_input=True),
        Case("one unreadable input, --skip-bad", imp + three + ["-o", f"{o}/c.npz", "--points", "UL,LL", "-q",
                                                               "--skip-bad"], 0, "skipped 1"),
        Case("full disk: 24-file --audio-dir import", imp + [str(p) for p in sorted(many.iterdir())] +
             ["-o", f"{d}/tiny/h.npz", "--audio-dir", f"{d}/tiny/aud", "-q"], 2, "No space left",
             mount="tmpfs:1M", loses_input=True),
        Case("full disk: figures", ["figures", m, "-o", f"{d}/tiny/figs", "-q"], 2, "No space left",
             mount="tmpfs:200k"),
        Case("full disk: build", ["build", c, "-o", f"{d}/tiny/m.npz", "-q"], 2, "No space left", mount="tmpfs:100k"),
        Case("read-only disk: synthesize -o and --mesh-dir", [S, "--manifold", m, "--phones", "p 0.1 aa 0.1", "-o",
                                                               f"{d}/tiny/t.csv", "--mesh-dir", f"{d}/tiny/mesh"], 2,
             "tiny/t.csv: Read-only", mount="ro"),
        # 4. stopped or failed at any moment: the complete old outputs or none
        Case("SIGTERM: synthesize --mesh-dir -o t.csv", [S, "--manifold", m, "--phones", "sil 4 aa 4 sil 4",
                                                         "--mesh-dir", f"{o}/mesh", "-o", f"{o}/t.csv", "-q"], None,
             None, [f"{o}/t.csv", f"{o}/mesh"], stop_after=30, stop_when="out/**/frame_0001*"),
        Case("SIGTERM: --audio-dir import of 24 files", imp + [str(p) for p in sorted(many.iterdir())] +
             ["-o", f"{o}/h.npz", "--audio-dir", f"{o}/aud", "-q"], None, None, [f"{o}/h.npz", f"{o}/aud"],
             stop_after=30, stop_when="out/**/F01_R03.wav"),
        Case("SIGTERM: figures", ["figures", m, "-o", f"{o}/figs", "-q"], None, None, [f"{o}/figs"], stop_after=30,
             stop_when="out/**/fig2b.png"),
        Case("SIGTERM: --force import keeps the old", imp + [str(p) for p in sorted(many.iterdir())] +
             ["-o", f"{o}/h.npz", "-q", "--force"], None, None, keep=[_old(o / "h.npz")], stop_after=4),
        # 5. damaged window state files: set aside, named, no traceback
        Case("autosave marker 'started': 'abc'", ["@py", marker.format(str(state / "a"), json.dumps(
            {"pid": 4242, "started": "abc"}))], 1, "refused:", never="Traceback"),
        Case("autosave marker not JSON", ["@py", marker.format(str(state / "b"), "{pid")], 1, "refused:"),
        Case("session 'extra' a list", ["@py", session.format(str(state / "s1.lipspace.json"),
                                                              s_json.format('"extra": [1, 2]'))], 1, "refused:"),
        Case("session NaN camera", ["@py", session.format(str(state / "s2.lipspace.json"), s_json.format(
            '"cameras": {"manifold": [[NaN, 0, 1], [0, 0, 0], [0, 1, 0]]}'))], 1, "refused:"),
        Case("settings file with damaged values", ["@py", settings.format(
            str(state / "cfg" / "lipspace.ini"), "[window]\ngeometry=@ByteArray(abc\nlayout_version=zz\n")], 1,
             "refused:"),
        # 6. messages: the user's file, the option typed, the real cause
        Case("--smoothing 1e9", [S, "--manifold", m, "--phones", "p 0.1 aa 0.1", "--smoothing", "1e9", "-o",
                                 f"{o}/t.csv"], 2, "--smoothing", [f"{o}/t.csv"], never="--inverse-dims"),
        Case("--smoothing inf", [S, "--manifold", m, "--phones", "p 0.1 aa 0.1", "--smoothing", "inf"], 2,
             "--smoothing"),
        Case("render --smoothing inf", ["render", "--manifold", m, "--phones", "p 0.1 aa 0.1", "--smoothing", "inf",
                                        "-o", f"{o}/v.mp4"], 2, "--smoothing", [f"{o}/v.mp4"]),
        Case("--key-frames 0,10^30", [S, "--manifold", m, "--utterance", uid, "--key-frames", "0," + "1" + "0" * 30,
                                      "-o", f"{o}/t.csv"], 2, "key frames", [f"{o}/t.csv"]),
        Case("ASCII terminal: info of a non-ASCII name", ["info", str(accentc)], 0, None,
             env={"PYTHONIOENCODING": "ascii"}),
        Case("ASCII terminal: import note", imp + [str(holes), "-o", f"{o}/café.npz", "--name", "café"], 0,
             "missing samples", env={"PYTHONIOENCODING": "ascii"}),
        Case("one-frame utterances", ["build", str(one), "-o", f"{o}/m.npz", "-q"], 2, "single frame",
             [f"{o}/m.npz"], never="never move"),
        Case("a coordinate of 1e30", ["build", str(hugec), "-o", f"{o}/m.npz", "-q"], 2, "1e+30", [f"{o}/m.npz"],
             never="shape.py"),
    ]
