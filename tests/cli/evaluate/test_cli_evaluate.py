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
    assert "--smoothing -1: must be from 0 to 3600 frames" in capsys.readouterr().err
    assert main(["evaluate", str(path), "--speaker-norm", "-q"]) == 2
    assert "names no speaker" in capsys.readouterr().err


def test_evaluate_protocols_on_the_haskins_pair(shared_data, capsys):
    assert main(["evaluate", "--haskins", str(shared_data / "haskins-ieee"), "-q"]) == 0
    out = capsys.readouterr().out
    assert "1 test utterance(s), 1 training" in out
    assert "per-speaker normalisation: each speaker's mean frame removed (F01, M01;" in out
    assert "no validation split" in out and "mean-frame" in out


def test_without_validation_the_calibrated_spline_is_never_behind_the_interpolations(shared_data):
    """The Haskins pair (one training sentence of the other speaker: no validation split). With the true X at
    the targets the manifold method, the spline with calibrated velocities, is not behind the state-velocity
    spline, PCHIP or linear over either test sentence's gaps, where the state-velocity spline alone is
    significantly behind PCHIP on M01 (the other speaker's velocities mislead). Through the states' own means
    there is nothing to calibrate: the method is the state-velocity spline there."""
    import numpy as np

    from app.cli.evaluate import name_haskins_speakers, normalise_per_speaker
    from engine.evaluation.paired import paired_comparison
    from engine.evaluation.protocols import evaluate_protocols
    from engine.io import read_corpus

    mats = sorted((shared_data / "haskins-ieee").glob("*.mat"))
    corpus = normalise_per_speaker(name_haskins_speakers(read_corpus([str(p) for p in mats])))
    for u in corpus.utterances:
        r = evaluate_protocols(corpus, test_ids=[u.id], inverse_table=False, phones=False)
        assert "no validation split" in r.settings["note"]
        for base in ("sv-hermite", "pchip", "linear"):
            c = r.comparison("oracle", base, "rmse_x")  # per gap: base's error - manifold's
            assert c["unit"] == "gaps" and c["n"] >= 25 and c["ci_high"] >= 0, (u.id, base, c)
        same = r.comparison("states", "sv-hermite", "rmse_x")
        assert same["wins"] == same["losses"] == 0 and same["mean_diff"] == 0  # identical trajectories
        if u.speaker == "M01":
            gap = {x["method"]: np.sqrt(np.array(x["gap_sq_x"]) / np.array(x["gap_frames"]))
                   for x in r._sums if x["protocol"] == "oracle"}
            spline = paired_comparison(gap["pchip"], gap["sv-hermite"])
            assert spline.ci_low > 0, spline  # the state-velocity spline alone: behind PCHIP on every resample
