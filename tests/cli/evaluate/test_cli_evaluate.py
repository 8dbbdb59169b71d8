"""`lipspace evaluate`: the equal-information protocols, CSV and Markdown output, the Haskins pair."""
import csv

from app.cli import main


def test_evaluate_prints_both_protocols(small_corpus, tmp_path, capsys):
    ids = [u.id for u in small_corpus.utterances]
    path = small_corpus.subset(ids[:8]).save(tmp_path / "c.npz")
    csv_out, md_out = tmp_path / "t.csv", tmp_path / "t.md"
    assert main(["evaluate", str(path), "--test-ids", f"{ids[3]},{ids[5]}", "--state-dims", "5", "--smoothing", "2",
                 "--neighbors", "20", "-q", "--csv", str(csv_out), "--markdown", str(md_out)]) == 0
    out = capsys.readouterr().out
    assert "2 test utterance(s), 6 training" in out
    assert "protocol 'states'" in out and "protocol 'oracle'" in out and "protocol 'phones'" in out
    assert "first 5 dims of F^y" in out and "k = 20" in out and "verdict X: manifold" in out
    rows = list(csv.DictReader(csv_out.read_text().splitlines()))
    assert list(rows[0]) == ["protocol", "method", "utterance", "rmse_x", "rmse_y", "lve", "vel", "smooth"]
    assert {r["method"] for r in rows} >= {"manifold", "viterbi", "linear", "pchip", "sv-hermite", "unitselection",
                                           "dominance", "sliding-window", "mean-frame"}
    assert {r["utterance"] for r in rows} == {ids[3], ids[5], "ALL"}
    assert all(float(r["lve"]) > 0 for r in rows)
    assert "Protocol `states`" in md_out.read_text()
    assert main(["evaluate", str(path), "--smoothing", "-1", "-q"]) == 2
    assert "--smoothing must be >= 0" in capsys.readouterr().err
    assert main(["evaluate", str(path), "--speaker-norm", "-q"]) == 2
    assert "names no speaker" in capsys.readouterr().err


def test_evaluate_protocols_on_the_haskins_pair(shared_data, capsys):
    assert main(["evaluate", "--haskins", "-q"]) == 0
    out = capsys.readouterr().out
    assert "1 test utterance(s), 1 training" in out and "per-speaker normalisation: each speaker's mean frame removed (F01, M01;" in out
    assert "no validation split" in out and "mean-frame" in out
