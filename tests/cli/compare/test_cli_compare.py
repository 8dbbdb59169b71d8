"""``lipspace compare``: a lab's recordings compared by speaker, a known difference found from a manifold file,
one sentence per speaker described but not tested, and bad input refused naming the field and levels."""
import contextlib
import csv
import io
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from app.cli import main
from engine.comparison.compare import COLUMNS


def _run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, out.getvalue(), err.getvalue()


def _rows(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def lab_corpus(lab_folder, tmp_path_factory):
    """The lab's nine recordings (three speakers, three each, 250 Hz, no phones) imported as a corpus file."""
    _, paths = lab_folder
    out = tmp_path_factory.mktemp("lab") / "lab.npz"
    rc, _, err = _run(["import", *map(str, paths), "--layout", "ema7x6", "-q", "--jobs", "1", "-o", str(out),
                       "--speaker-from", "re:^([A-Z]{3})"])
    assert rc == 0, err
    return out


def _with_speakers(corpus, speakers):
    return replace(corpus, utterances=[replace(u, speaker=s) for u, s in zip(corpus.utterances, speakers)])


@pytest.fixture(scope="module")
def conditions_file(conditions, tmp_path_factory):
    """The conditions' manifold saved with each utterance's condition as its speaker (the field files keep)."""
    cc, m = conditions
    path = tmp_path_factory.mktemp("cond") / "m.npz"
    original = m.corpus_
    m.corpus_ = _with_speakers(original, cc.fields["condition"])
    try:
        m.save(path)
    finally:
        m.corpus_ = original
    return path


def test_a_lab_corpus_compared_by_speaker_from_a_corpus_file(lab_corpus, tmp_path):
    stats, fig = tmp_path / "stats.csv", tmp_path / "diff.pdf"
    rc, out, err = _run(["compare", str(lab_corpus), "--by", "speaker", "--levels", "ABC,KLM", "--csv", str(stats),
                         "--figure", str(fig), "--width", "85mm", "--permutations", "199", "--bootstrap", "50", "-q"])
    assert rc == 0, err
    assert "field 'speaker' (ABC 3, KLM 3, XYM 3 utterances)" in out
    assert "design: between utterances: ABC 3 vs KLM 3 utterances; utterances exchangeable" in out
    assert "note: the speakers are compared as individuals" in err
    assert "speaker normalisation mean over 3 speakers: each speaker's mean lip shape was removed first" in err
    assert "has no phone labels: using" in err and "kinematic landmarks" in err  # the clusters are landmarks
    rows = _rows(stats)
    assert list(rows[0]) == list(COLUMNS)
    assert {r["family"] for r in rows} == {"cluster", "dynamics", "state"}
    assert all(r["level_a"] == "ABC" and r["level_b"] == "KLM" for r in rows)
    assert {r["target"] for r in rows if r["family"] == "cluster"} <= {"open", "closed", "opening", "closing"}
    p = [float(r["p"]) for r in rows]
    assert min(p) >= 1 / 20 - 1e-9  # 20 arrangements of 3 + 3 utterances: exact, p never below 1/20
    assert fig.stat().st_size > 1000 and fig.read_bytes()[:4] == b"%PDF"
    assert not list(tmp_path.glob(".*part*"))


def test_a_known_difference_from_a_manifold_file(conditions_file, tmp_path):
    stats = tmp_path / "stats.csv"
    rc, out, err = _run(["compare", str(conditions_file), "--by", "speaker", "--levels", "a,b", "--paired-by", "text",
                         "--csv", str(stats), "--permutations", "999", "--bootstrap", "100", "-q"])
    assert rc == 0, err
    assert "design: within blocks: a 20 vs b 20 utterances; labels permuted within 10 text blocks" in out
    clusters = out.split("\nclusters (smallest p first)\n")[1].splitlines()
    assert clusters[2].split()[2] in ("b", "p")  # the first row under the header: a bilabial
    rows = _rows(stats)
    dyn = {r["target"]: r for r in rows if r["measure"] == "opening speed"}
    assert float(dyn["while opening"]["estimate"]) > 1.05 and float(dyn["while opening"]["q"]) < 0.05
    assert all("999 permutations" in r["design"] for r in rows)


def test_one_sentence_per_speaker_is_described_but_not_tested(conditions, tmp_path):
    cc, m = conditions
    # the same sentence said once by each of two 'speakers' (the way the Haskins pair is)
    ids = [m.corpus_.utterances[0].id, m.corpus_.utterances[2].id]
    pair = _with_speakers(m.corpus_.subset(ids), ["F01", "M01"])
    path = pair.save(tmp_path / "pair.npz")
    stats, fig = tmp_path / "stats.csv", tmp_path / "diff.png"
    rc, out, err = _run(["compare", str(path), "--by", "speaker", "--paired-by", "text", "--csv", str(stats),
                         "--figure", str(fig), "-q"])
    assert rc == 0, err
    assert "lipspace compare: cannot test M01 against F01: one utterance per level (F01: 1, M01: 1)" in err
    assert "cannot test: one utterance per level" in out and "The estimates describe these utterances only" in out
    rows = _rows(stats)
    assert rows and all(r["p"] in ("", "nan") and r["q"] in ("", "nan") for r in rows)
    assert all(math.isfinite(float(r["estimate"])) for r in rows if r["family"] == "dynamics")
    assert fig.stat().st_size > 1000


@pytest.mark.parametrize("extra, message", [
    (["--by", "emotion"], "has no field 'emotion'; its fields: speaker (3 levels)"),
    (["--by", "speaker"], "field 'speaker' has 3 levels: ABC (3), KLM (3), XYM (3); choose two"),
    (["--by", "speaker", "--levels", "ABC,QQQ"], "field 'speaker' has no level 'QQQ'; its levels (utterances): "
                                                 "ABC (3), KLM (3), XYM (3)"),
    (["--by", "speaker", "--levels", "ABC"], "give at least two levels"),
    (["--by", "speaker", "--paired-by", "speaker", "--levels", "ABC,KLM"], "cannot also be the pairing field"),
    (["--by", "speaker", "--levels", "ABC,KLM", "--paired-by", "text"], "has no field 'text'"),
    (["--by", "speaker", "--figure", "x.jpg"], "--figure x.jpg: the figure must end in .pdf, .png, .svg"),
    (["--by", "speaker", "--alpha", "2"], "--alpha 2: must be between 0 and 1"),
])
def test_bad_input_is_refused_naming_the_field_and_levels(lab_corpus, tmp_path, extra, message):
    rc, out, err = _run(["compare", str(lab_corpus), *extra, "--csv", str(tmp_path / "s.csv"), "-q"])
    assert rc == 2
    assert message in err and "Traceback" not in err
    assert not (tmp_path / "s.csv").exists()


def test_levels_that_never_share_a_sentence_are_refused(conditions, tmp_path):
    cc, m = conditions
    texts = cc.fields["text"]
    first = np.flatnonzero(texts == texts[0])[0]
    other = np.flatnonzero(texts != texts[0])[0]
    ids = [m.corpus_.utterances[first].id, m.corpus_.utterances[other].id]
    path = _with_speakers(m.corpus_.subset(ids), ["A", "B"]).save(tmp_path / "c.npz")
    rc, _, err = _run(["compare", str(path), "--by", "speaker", "--paired-by", "text", "-q"])
    assert rc == 2
    assert "levels 'A' and 'B' of 'speaker' never share a text: no text value has utterances of both" in err


def test_an_existing_output_is_refused_before_any_work_and_replaced_with_force(lab_corpus, tmp_path):
    stats = tmp_path / "stats.csv"
    stats.write_text("old")
    argv = ["compare", str(lab_corpus), "--by", "speaker", "--levels", "ABC,KLM", "--csv", str(stats),
            "--permutations", "19", "--bootstrap", "0", "-q"]
    rc, _, err = _run(argv)
    assert rc == 2 and "--csv" in err and "already exists" in err and stats.read_text() == "old"
    rc, _, err = _run([*argv, "--force"])
    assert rc == 0, err
    assert _rows(stats)[0]["field"] == "speaker"


def test_a_stop_during_the_resampling_writes_nothing(lab_corpus, tmp_path, monkeypatch):
    import engine.comparison.compare as compare

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(compare, "run_families", interrupted)
    stats, fig = tmp_path / "stats.csv", tmp_path / "diff.pdf"
    rc, _, err = _run(["compare", str(lab_corpus), "--by", "speaker", "--levels", "ABC,KLM", "--csv", str(stats),
                       "--figure", str(fig), "-q"])
    assert rc == 130 and "interrupted; nothing was written" in err
    assert not stats.exists() and not fig.exists() and not list(tmp_path.glob(".*part*"))


def test_the_guide_s_haskins_comparison(shared_data, tmp_path):
    """docs/USER_GUIDE.md, "Comparing conditions": the two Haskins sentences, import -> build -> compare."""
    files = sorted(str(p) for p in (shared_data / "haskins-ieee").glob("*.mat"))
    if len(files) < 2:
        pytest.skip("the Haskins IEEE pair is not in ../shared/data/haskins-ieee")
    corpus, mfile = tmp_path / "haskins.npz", tmp_path / "haskins-m.npz"
    assert _run(["import", *files, "--speaker-from", "prefix", "-o", str(corpus), "-q"])[0] == 0
    assert _run(["build", str(corpus), "-o", str(mfile), "-q"])[0] == 0
    stats, fig = tmp_path / "stats.csv", tmp_path / "diff.pdf"
    rc, out, err = _run(["compare", str(mfile), "--by", "speaker", "--paired-by", "text", "--csv", str(stats),
                         "--figure", str(fig), "-q"])
    assert rc == 0, err
    guide = (Path(__file__).resolve().parents[3] / "docs" / "USER_GUIDE.md").read_text(encoding="utf-8")
    for line in out.splitlines()[:5]:
        if line.startswith(("design:", "cannot test:", "F01_")):
            assert line in guide, line
    rows = {(r["measure"], r["target"], r["space"]): r for r in _rows(stats)}
    assert float(rows[("opening speed", "while opening", "")]["estimate"]) == pytest.approx(0.65, abs=0.005)
    assert float(rows[("centre shift", "DH", "X")]["estimate"]) == pytest.approx(1.42, abs=0.005)
    assert fig.stat().st_size > 1000
