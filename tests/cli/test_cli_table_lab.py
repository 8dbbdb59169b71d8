"""``lipspace table`` and ``evaluate`` for a lab: metadata fields as columns, derived tracks, one row per gesture
with its landmark times, durations, peak velocities and manifold states, gesture tiers in the TextGrids, the
per-gesture table read in R, and errors per level of a field."""
from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest

PATTERN = r"re:^(?P<speaker>[A-Z]+?)(?P<sex>[FM])(?P<emotion>[A-Z]{2})(?P<text>[0-9]+)$"
RSCRIPT = shutil.which("Rscript")
needs_r = pytest.mark.skipif(RSCRIPT is None, reason="R is not installed (apt-get install r-base-core; .ci/run does)")


@pytest.fixture(scope="module")
def lab_files(ag501_lab, tmp_path_factory, cli):
    """(corpus file, manifold file) of the lab folder imported with its fields, bad samples masked."""
    folder, *_ = ag501_lab
    d = tmp_path_factory.mktemp("labtable")
    rc, _, err = cli(["import", str(folder), "--layout", str(folder / "lab.layout"), "--fields-from", PATTERN,
                      "--quality", "mask", "-q", "--jobs", "1", "-o", str(d / "corpus.npz")])
    assert rc == 0, err
    rc, _, err = cli(["build", str(d / "corpus.npz"), "-o", str(d / "manifold.npz"), "-q"])
    assert rc == 0, err
    return d / "corpus.npz", d / "manifold.npz"


@pytest.fixture(scope="module")
def written(lab_files, tmp_path_factory, cli):
    d = tmp_path_factory.mktemp("labout")
    rc, out, err = cli(["table", str(lab_files[1]), "-o", str(d / "frames.csv"), "--tracks",
                        "lip_protrusion,speed_UL,LL_up,rms_UL", "--gestures", "lip_aperture,lip_protrusion",
                        "--gesture-table", str(d / "gestures.csv"), "--textgrid", str(d / "grids")])
    assert rc == 0, err
    return d, out, err


def test_fields_are_columns_after_speaker_and_tracks_are_appended(written):
    pd = pytest.importorskip("pandas")
    d, out, _ = written
    f = pd.read_csv(d / "frames.csv")
    assert list(f.columns[:6]) == ["utterance", "speaker", "sex", "emotion", "text", "time_s"]
    assert list(f.columns[-4:]) == ["lip_protrusion", "speed_ul", "ll_up", "rms_ul"]
    assert set(f["emotion"]) == {"NE", "AN", "SA"} and set(f["sex"]) == {"F", "M"}
    assert f["text"].dtype.kind == "i" or set(f["text"].astype(str)) <= {"1", "2", "01", "02"}
    assert (f["speed_ul"] >= 0).all() and f["rms_ul"].notna().all()
    meta = json.loads((d / "frames.csv.json").read_text())
    assert meta["columns"]["speed_ul"]["unit"] == "mm/s" and "low-passed at 15 Hz" in \
        meta["columns"]["speed_ul"]["description"]
    assert any("zero phase" in n for n in meta["notes"])


def test_one_row_per_gesture_with_landmarks_durations_speeds_and_states(written, lab_files):
    pd = pytest.importorskip("pandas")
    from engine.manifold.model import Manifold
    from engine.recordings.signals.gestures import find_gestures

    d, out, err = written
    g = pd.read_csv(d / "gestures.csv")
    m = Manifold.load(lab_files[1])
    want = find_gestures(m.corpus_, "lip_aperture")
    ga = g[g["track"] == "lip_aperture"]
    assert len(ga) == len(want) and set(g["track"]) == {"lip_aperture", "lip_protrusion"}
    assert f"{len(want)} gestures of lip_aperture (to a minimum" in err and "wrote" in out
    np.testing.assert_allclose(ga["maxc_s"], want.times[:, 3], rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(ga["gesture_s"], ga["goffs_s"] - ga["gons_s"], rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(ga["nucleus_s"], ga["noffs_s"] - ga["nons_s"], rtol=1e-5, atol=1e-6)
    frames = want.frames(m.corpus_.bounds)[:, 3]
    np.testing.assert_array_equal(ga["state_maxc"].to_numpy(), m.states_.labels_[frames])
    assert (ga["pvel_toward"] > 0).all() and set(g["emotion"]) == {"NE", "AN", "SA"}
    assert set(g[g["track"] == "lip_protrusion"]["target"]) == {"max"}
    meta = json.loads((d / "gestures.csv.json").read_text())
    assert meta["columns"]["gons_s"]["unit"] == "s" and "20 % of each peak speed" in meta["notes"][0]


def test_textgrids_have_a_gesture_tier_per_track(written, lab_files):
    from engine.io.readers.alignment import _parse_textgrid
    from engine.manifold.model import Manifold
    from engine.recordings.signals.gestures import find_gestures

    d, _, _ = written
    m = Manifold.load(lab_files[1])
    gs = find_gestures(m.corpus_, "lip_aperture")
    u = m.corpus_.utterances[0]
    g = _parse_textgrid(d / "grids" / f"{u.id}.TextGrid")
    assert list(g) == ["phones", "class", "landmarks", "gestures", "gestures_lip_protrusion"]
    assert g["gestures"].is_point_tier
    n = int(np.isfinite(gs.times[gs.of_utterance(u.id)]).sum())
    labels = [p.text for p in g["gestures"]]
    assert sum(lab.count("+") + 1 for lab in labels) == n and labels[0] in ("GONS", "PVEL")


def test_praat_reads_the_gesture_tiers(written, praat):
    out = praat('form F\n  sentence f x\nendform\nRead from file: f$\nn = Get number of points: 4\n'
                't$ = Get tier name: 4\nwriteInfoLine: t$, " ", n\n', next((written[0] / "grids").glob("*.TextGrid")))
    name, n = out.split()
    assert name == "gestures" and int(n) > 0


@needs_r
def test_r_reads_the_gesture_table_and_summarises_by_emotion(written, tmp_path):
    code = ('g <- readr::read_csv(f, show_col_types = FALSE)\n'
            'a <- g[g$track == "lip_aperture", ]\n'
            's <- aggregate(nucleus_s ~ emotion, data = a, FUN = mean)\n'
            'cat(nrow(g), is.numeric(g$gons_s), is.character(g$emotion), nrow(s), sum(is.na(g$maxc_s)), "\\n")\n')
    r = subprocess.run([RSCRIPT, "-e", f'f <- "{written[0] / "gestures.csv"}"', "-e", code], capture_output=True,
                       text=True, timeout=120)
    if "there is no package called" in r.stderr:
        pytest.skip("R has no readr")
    assert r.returncode == 0, r.stderr
    n, num, chr_, levels, na = r.stdout.split()
    rows = len((written[0] / "gestures.csv").read_text().splitlines()) - 1
    assert int(n) == rows and num == "TRUE" and chr_ == "TRUE" and int(levels) == 3 and int(na) == 0


def test_table_options_that_cannot_be_followed_are_refused(lab_files, tmp_path, cli):
    m = str(lab_files[1])
    rc, _, err = cli(["table", m, "-o", str(tmp_path / "f.csv"), "--tracks", "speed_TT"])
    assert rc == 2 and "--tracks speed_TT: " in err and "has no such track" in err and "speed_UL" in err
    rc, _, err = cli(["table", m, "--gesture-table", str(tmp_path / "g.csv")])
    assert rc == 2 and "--gesture-table needs --gestures TRACK" in err
    rc, _, err = cli(["table", m, "-o", str(tmp_path / "f.csv"), "--tracks", "UL_up", "--lowpass", "45"])
    assert rc == 2 and "--lowpass: low-pass cut-off 45 Hz: must be above 0 and below the Nyquist frequency 30 Hz" in err
    rc, _, err = cli(["table", m, "--gestures", "UL_up", "--gesture-table", str(tmp_path / "g.csv")])
    assert rc == 2 and "say whether its gestures move to a minimum or a maximum" in err
    assert not list(tmp_path.iterdir())
    rc, out, _ = cli(["table", m, "--tracks", "list"])
    assert rc == 0 and "lip_protrusion" in out.split() and "rms_UL" in out.split()


@pytest.mark.slow
def test_evaluate_reports_errors_per_level_of_a_field(lab_files, tmp_path, cli):
    rc, out, err = cli(["evaluate", str(lab_files[0]), "--by", "emotion", "-q", "--test-ids",
                        "XYZFNE02,EFFAN01,ABCDMSA01,EFFSA01", "--state-dims", "4", "--smoothing", "1",
                        "--neighbors", "8", "--csv", str(tmp_path / "e.csv")])
    assert rc == 0, err
    assert "per level of 'emotion'" in out and "AN (n=1)" in out and "SA (n=2)" in out
    head = (tmp_path / "e.csv").read_text().splitlines()[0]
    assert head.startswith("protocol,method,utterance,emotion,")
    lv = (tmp_path / "e-levels.csv").read_text().splitlines()
    assert lv[0] == "field,level,protocol,method,utterances,frames,rmse_x,rmse_y,lve,vel"
    assert any(x.startswith("emotion,SA,states,manifold,2,") for x in lv)


def test_evaluate_by_a_field_the_corpus_lacks_stops_before_the_work(lab_files, cli):
    rc, _, err = cli(["evaluate", str(lab_files[0]), "--by", "group", "-q"])
    assert rc == 2 and "--by group: " in err and "its fields: speaker, sex, emotion, text" in err


def test_gestural_landmarks_are_synthesis_targets(lab_files, tmp_path, cli):
    from engine.manifold.model import Manifold
    from engine.recordings.signals.gestures import find_gestures, gesture_key_frames

    m = Manifold.load(lab_files[1])
    u = m.corpus_.utterances[2]
    want = gesture_key_frames(find_gestures(m.corpus_, "lip_aperture"), u.id, m.corpus_.bounds,
                              landmarks=("GONS", "MAXC", "GOFFS"))
    rc, out, err = cli(["synthesize", "--manifold", str(lab_files[1]), "--utterance", u.id, "--key-frames",
                        "gestures:GONS+MAXC+GOFFS", "--method", "linear", "-o", str(tmp_path / "t.csv"),
                        "-q"])
    assert rc == 0, err
    assert f"through {want.size} targets from utterance {u.id!r}" in out
    rc, _, err = cli(["synthesize", "--manifold", str(lab_files[1]), "--utterance", u.id, "--key-frames",
                      "gestures:PEAK", "--method", "linear", "-o", str(tmp_path / "u.csv"), "-q"])
    assert rc == 2 and "landmark(s) ['PEAK']; expected some of GONS, PVEL, NONS, MAXC, NOFFS, PVEL2, GOFFS" in err


def _guide_gesture_snippet() -> str:
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "USER_GUIDE.md").read_text(encoding="utf-8")
    m = re.search(r"<!-- r-gesture-snippet -->\n```r\n(.*?)```", text, re.S)
    assert m, "docs/USER_GUIDE.md has no R snippet after <!-- r-gesture-snippet -->"
    return m.group(1)


@needs_r
def test_the_guides_r_snippet_summarises_the_gesture_table(written, tmp_path):
    shutil.copy(written[0] / "gestures.csv", tmp_path / "gestures.csv")
    (tmp_path / "g.R").write_text("r <- local({\n" + _guide_gesture_snippet() + "})\nprint(r)\n"
                                  'cat("ROWS", nrow(r), ncol(r), "\\n")\n')
    r = subprocess.run([RSCRIPT, "g.R"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    if "there is no package called" in r.stderr:
        pytest.skip("R has no readr")
    assert r.returncode == 0, r.stderr
    rows, cols = r.stdout.split("ROWS")[1].split()
    assert int(rows) == 9 and int(cols) == 4  # 3 speakers x 3 emotions: speaker, emotion, nucleus_s, pvel_toward
