"""``lipspace table``: the tidy per-frame table read by pandas and R without options, TextGrids that open in
Praat and read back with praat-textgrids, and no file replaced without --force.

pandas is in the ``test`` extra (the project itself does not need it); the Praat and R checks run the real
programs (Debian's ``praat`` and ``r-base-core``, installed by ``.ci/run``) and are skipped where they are absent.
"""
from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from app.cli import main

REPO = Path(__file__).resolve().parents[2]
RSCRIPT = shutil.which("Rscript")
needs_r = pytest.mark.skipif(RSCRIPT is None, reason="R is not installed (apt-get install r-base-core; .ci/run does)")


@pytest.fixture(scope="module")
def mfile(small_manifold, tmp_path_factory):
    return small_manifold.save(tmp_path_factory.mktemp("table") / "m.npz")


@pytest.fixture(scope="module")
def written(mfile, tmp_path_factory):
    d = tmp_path_factory.mktemp("out")
    assert main(["table", str(mfile), "-o", str(d / "frames.csv"), "--textgrid", str(d / "grids")]) == 0
    return d


def test_the_csv_reads_in_pandas_without_options(written, small_manifold):
    pd = pytest.importorskip("pandas")
    from engine.manifold.frame_table import CLASS_LABELS, frame_table

    d = pd.read_csv(written / "frames.csv")
    c = small_manifold.corpus_
    t = frame_table(small_manifold)
    assert list(d.columns) == list(t.columns) and len(d) == c.n_frames
    assert all(re.fullmatch(r"[a-z][a-z0-9_]*", n) for n in d.columns)
    assert d["time_s"].dtype.kind == "f" and d["frame"].dtype.kind == "i" and d["state"].dtype.kind == "i"
    assert d["class"].isna().sum() == 0  # every frame of an utterance longer than one frame has a step
    assert set(d["class"].dropna()) <= set(CLASS_LABELS)
    assert set(d["speaker"]) == {"unknown"}  # the talker names no speakers: a word R reads as text, not NA
    from engine.recordings.kinematics import lip_aperture

    np.testing.assert_allclose(d["lip_aperture"], lip_aperture(c), rtol=1e-6, atol=1e-5)
    np.testing.assert_allclose(d["v"], t.columns["v"], rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(d["phone"].fillna("").to_numpy(), np.array([x or "" for x in t.columns["phone"]]))
    meta = json.loads((written / "frames.csv.json").read_text())
    assert set(meta["columns"]) == set(d.columns) and meta["rows"] == len(d) and meta["missing_values"] == "NA"
    assert meta["columns"]["time_s"]["unit"] == "s" and meta["columns"]["lip_aperture"]["unit"] == "mm"


def test_parquet_holds_the_same_columns_with_their_units(mfile, written, tmp_path):
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    out = tmp_path / "frames.parquet"
    assert main(["table", str(mfile), "-o", str(out), "--fx", "3"]) == 0
    p, c = pd.read_parquet(out), pd.read_csv(written / "frames.csv")
    assert list(p.columns) == [n for n in c.columns if not n.startswith("fx_") or n in ("fx_1", "fx_2", "fx_3")]
    np.testing.assert_allclose(p["v"], c["v"], rtol=1e-6, atol=1e-6)
    assert p["class"].isna().sum() == c["class"].isna().sum()
    import pyarrow.parquet as pq

    meta = json.loads(pq.read_schema(out).metadata[b"lipspace"])
    assert meta["columns"]["fx_1"]["unit"] == "shape-space units (F^x)"
    assert json.loads((tmp_path / "frames.parquet.json").read_text()) == meta


def test_without_pyarrow_parquet_is_refused_with_the_fix(mfile, tmp_path, monkeypatch, capsys):
    import engine.io.writers.tidy as tidy

    monkeypatch.setattr(tidy, "have_parquet", lambda: False)
    assert main(["table", str(mfile), "-o", str(tmp_path / "f.parquet")]) == 2
    assert "lipspace[parquet]" in capsys.readouterr().err and not list(tmp_path.iterdir())


def test_nothing_is_replaced_without_force(mfile, tmp_path, capsys):
    out = tmp_path / "frames.csv"
    out.write_text("keep me")
    assert main(["table", str(mfile), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{out}: already exists" in err and "--force" in err and out.read_text() == "keep me"
    assert not (tmp_path / "frames.csv.json").exists()
    grids = tmp_path / "grids"
    grids.mkdir()
    (grids / "s0003.TextGrid").write_text("mine")
    (grids / "notes.txt").write_text("other files stay")
    assert main(["table", str(mfile), "--textgrid", str(grids)]) == 2
    assert "s0003.TextGrid" in (e := capsys.readouterr().err) and "already exists" in e
    assert sorted(p.name for p in grids.iterdir()) == ["notes.txt", "s0003.TextGrid"]
    assert main(["table", str(mfile), "-o", str(out), "--textgrid", str(grids), "--force"]) == 0
    assert out.read_text().startswith("utterance,speaker,time_s,") and (grids / "notes.txt").exists()
    assert (grids / "s0003.TextGrid").read_text().startswith('File type = "ooTextFile"')
    assert main(["table", str(mfile)]) == 2 and "nothing to write" in capsys.readouterr().err


def test_textgrids_read_back_with_praat_textgrids(written, small_manifold):
    from engine.io import read_textgrid
    from engine.io.readers.alignment import _parse_textgrid
    from engine.manifold.frame_table import class_intervals, frame_table

    c = small_manifold.corpus_
    t = frame_table(small_manifold)
    files = sorted((written / "grids").glob("*.TextGrid"))
    assert [f.stem for f in files] == sorted(u.id for u in c.utterances)
    for u in c.utterances:
        f = written / "grids" / f"{u.id}.TextGrid"
        g = _parse_textgrid(f)
        assert list(g) == ["phones", "class", "landmarks"] and g["landmarks"].is_point_tier
        assert [(p.start, p.end, p.label) for p in read_textgrid(f, tier="phones")] == \
            [(p.start, p.end, p.label) for p in u.phones]
        runs = class_intervals(t.columns["class"][u.start:u.stop], c.rate)
        assert [iv.text for iv in g["class"] if iv.text] == [r[2] for r in runs]
        assert len(g["landmarks"]) == sum(x is not None for x in t.columns["landmark"][u.start:u.stop])


def _expected_counts(path):
    from engine.io.readers.alignment import _parse_textgrid

    g = _parse_textgrid(path)
    return {name: (0 if tier.is_point_tier else 1, len(tier)) for name, tier in g.items()}, g.xmin, g.xmax


def test_every_textgrid_opens_in_praat_with_its_tiers_and_counts(written, praat):
    grids = written / "grids"
    out = praat(
        "form Check\n  sentence dir x\nendform\n"
        'list = Create Strings as file list: "list", dir$ + "/*.TextGrid"\n'
        "n = Get number of strings\n"
        "for i to n\n  selectObject: list\n  name$ = Get string: i\n"
        '  tg = Read from file: dir$ + "/" + name$\n  nt = Get number of tiers\n  line$ = name$\n'
        "  for t to nt\n    tname$ = Get tier name: t\n    isint = Is interval tier: t\n"
        "    if isint\n      k = Get number of intervals: t\n    else\n      k = Get number of points: t\n    endif\n"
        '    line$ = line$ + tab$ + tname$ + ":" + string$ (isint) + ":" + string$ (k)\n  endfor\n'
        "  xmin = Get start time\n  xmax = Get end time\n"
        '  appendInfoLine: line$, tab$, fixed$ (xmin, 9), tab$, fixed$ (xmax, 9)\n  removeObject: tg\nendfor\n', grids)
    lines = out.strip().splitlines()
    assert len(lines) == len(list(grids.glob("*.TextGrid")))
    for line in lines:
        name, *tiers, xmin, xmax = line.split("\t")
        want, wmin, wmax = _expected_counts(grids / name)
        got = {}
        for item in tiers:
            tname, isint, k = item.rsplit(":", 2)
            got[tname] = (int(isint), int(k))
        assert got == want, name
        assert float(xmin) == pytest.approx(wmin, abs=1e-9) and float(xmax) == pytest.approx(wmax, abs=1e-8)


def test_praat_reads_labels_with_quotes_and_non_ascii(tmp_path, praat):
    from engine.io.writers.praat import IntervalTier, PointTier, write_textgrid

    p = write_textgrid(tmp_path / "q.TextGrid", 0, 1, [IntervalTier("w", [(0.2, 0.4, 'say "hi"'), (0.4, 0.6, "ʃøn")]),
                                                      PointTier("p", [(0.5, "é")])])
    out = praat("form Q\n  sentence f x\nendform\nRead from file: f$\n"
                "a$ = Get label of interval: 1, 2\nb$ = Get label of interval: 1, 3\nc$ = Get label of point: 2, 1\n"
                'writeInfoLine: a$, "|", b$, "|", c$\n', p)
    assert out.strip() == 'say "hi"|ʃøn|é'


def _csv_shape(path) -> tuple[int, int]:
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    return len(lines) - 1, len(lines[0].split(","))


def _readme_r_snippet() -> str:
    """The R snippet of the user guide (docs/USER_GUIDE.md, "From Lipspace to R / Praat")."""
    text = (REPO / "docs" / "USER_GUIDE.md").read_text(encoding="utf-8")
    m = re.search(r"<!-- r-snippet -->\n```r\n(.*?)```", text, re.S)
    assert m, "docs/USER_GUIDE.md has no R snippet after <!-- r-snippet -->"
    return m.group(1)


def test_the_readme_r_snippet_is_five_lines_reading_frames_csv():
    code = _readme_r_snippet()
    assert len(code.strip().splitlines()) == 5 and 'read.csv("frames.csv")' in code and "class" in code


@needs_r
def test_the_readme_r_snippet_plots_aperture_by_class_in_r(written, tmp_path):
    shutil.copy(written / "frames.csv", tmp_path / "frames.csv")
    (tmp_path / "plot.R").write_text(_readme_r_snippet() + 'cat(nrow(d), y, nlevels(factor(d$class)), "\\n")\n')
    r = subprocess.run([RSCRIPT, "plot.R"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    rows, y, k = r.stdout.split()
    n = _csv_shape(written / "frames.csv")[0]
    assert int(rows) == n and y == "lip_aperture" and int(k) == 4  # every frame has a class
    png = (tmp_path / "aperture_by_class.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 2000


@pytest.fixture(scope="module")
def unlabelled_manifold():
    """A 4-sensor articulograph corpus (250 Hz, imported at 60 Hz) with no phone labels and no speaker names."""
    import warnings
    from dataclasses import replace

    from engine.manifold.model import Manifold
    from engine.talker.example_corpora import articulograph_corpus

    c = articulograph_corpus(n_speakers=1, n_utterances=3, duration_s=(2.0, 2.6), seed=3)
    c = replace(c, utterances=[replace(u, speaker="") for u in c.utterances])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a short corpus's state warnings are not what this tests
        return Manifold(n_states=12).fit(c)


def test_textgrids_end_where_the_recording_does(unlabelled_manifold, tmp_path):
    """A 250 Hz recording of n samples lasts n / 250 s; at 60 Hz its frames round that up to a whole frame.
    The TextGrid ends at the recording's end, not at the last frame's."""
    from engine.io import read_textgrid  # noqa: F401 - the grids read back below
    from engine.talker.multispeaker import generate_recordings

    m = unlabelled_manifold
    path = m.save(tmp_path / "m.npz")
    assert main(["table", str(path), "--textgrid", str(tmp_path / "g")]) == 0
    recs = generate_recordings(n_speakers=1, n_utterances=3, duration_s=(2.0, 2.6), seed=3)
    for u, r in zip(m.corpus_.utterances, recs):
        true = r.matrix.shape[0] / r.rate
        assert u.duration_s == pytest.approx(true) and u.n_frames / m.corpus_.rate > true + 1e-6
        text = (tmp_path / "g" / f"{u.id}.TextGrid").read_text()
        assert re.search(r"^xmax = ([0-9.]+) ", text, re.M).group(1) == repr(true).rstrip("0").rstrip(".") or \
            float(re.search(r"^xmax = ([0-9.]+) ", text, re.M).group(1)) == pytest.approx(true, abs=1e-9)


def _r_types(path):
    """``(read.csv's, readr's)`` lines for the frame table at ``path``: rows, columns, then the class of time_s,
    frame, class, speaker, phone and the missing values of class (readr: "no readr" when it is not installed)."""
    cols = "c('time_s', 'frame', 'class', 'speaker', 'phone')"
    code = (f'd <- read.csv(f); cat(nrow(d), ncol(d), sapply(d[{cols}], function(x) class(x)[1]), '
            'sum(is.na(d$class)), "\\n")\n'
            'if (requireNamespace("readr", quietly = TRUE)) { e <- readr::read_csv(f, show_col_types = FALSE); '
            f'cat(nrow(e), ncol(e), sapply(e[{cols}], function(x) class(x)[1]), sum(is.na(e$class)), "\\n") }} '
            'else cat("no readr\\n")\n')
    r = subprocess.run([RSCRIPT, "-e", f'f <- "{path}"', "-e", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    return r.stdout.strip().splitlines()


@needs_r
def test_r_reads_the_types_and_missing_values_without_options(written, tmp_path):
    base, rd = _r_types(written / "frames.csv")
    n, ncol = _csv_shape(written / "frames.csv")
    assert base.split() == [str(n), str(ncol), "numeric", "integer", "character", "character", "character", "0"]
    if rd != "no readr":
        assert rd.split() == [str(n), str(ncol), "numeric", "numeric", "character", "character", "character", "0"]


@needs_r
def test_r_reads_speaker_and_phone_as_text_for_a_corpus_that_names_neither(unlabelled_manifold, tmp_path):
    """A label-less corpus whose utterances name no speaker: both columns are text in R (never all NA)."""
    path = unlabelled_manifold.save(tmp_path / "m.npz")
    assert main(["table", str(path), "-o", str(tmp_path / "f.csv")]) == 0
    base, rd = _r_types(tmp_path / "f.csv")
    n, ncol = _csv_shape(tmp_path / "f.csv")
    assert base.split() == [str(n), str(ncol), "numeric", "integer", "character", "character", "character", "0"]
    if rd != "no readr":
        assert rd.split()[4:7] == ["character", "character", "character"]
    meta = json.loads((tmp_path / "f.csv.json").read_text())
    assert "unknown" in meta["columns"]["speaker"]["description"]
    assert "unlabelled" in meta["columns"]["phone"]["description"]


def test_a_real_recording_gets_its_lip_aperture_and_its_own_phones(mocha_manifold, tmp_path):
    pd = pytest.importorskip("pandas")
    from engine.io import read_textgrid
    from engine.recordings.kinematics import lip_aperture

    m = mocha_manifold
    mfile = m.save(tmp_path / "mocha.npz")
    assert main(["table", str(mfile), "-o", str(tmp_path / "f.csv"), "--textgrid", str(tmp_path / "g")]) == 0
    f = pd.read_csv(tmp_path / "f.csv")
    assert "lip_aperture" in f.columns and "opening_fx1" not in f.columns
    np.testing.assert_allclose(f["lip_aperture"], lip_aperture(m.corpus_), rtol=1e-6)
    meta = json.loads((tmp_path / "f.csv.json").read_text())
    assert meta["columns"]["lip_aperture"]["unit"] == "mm"
    u = m.corpus_.utterances[0]
    grid = tmp_path / "g" / f"{u.id}.TextGrid"
    assert [(p.start, p.end, p.label) for p in read_textgrid(grid, tier="phones")] == \
        [(p.start, p.end, p.label) for p in u.phones]
