import csv

import numpy as np
import pytest

from app.cli import main


@pytest.fixture(scope="module")
def mfile(small_manifold, tmp_path_factory):
    return small_manifold.save(tmp_path_factory.mktemp("synth") / "m.npz")


def test_phones_to_csv_and_obj_meshes(mfile, small_manifold, tmp_path, capsys):
    out = tmp_path / "traj.csv"
    meshes = tmp_path / "mesh"
    assert main(["synthesize", "--manifold", str(mfile), "--phones", "sil 0.15 m 0.08 aa 0.12 p 0.08 sil 0.15",
                 "-o", str(out), "--mesh-dir", str(meshes)]) == 0
    text = capsys.readouterr().out
    # the default method is the one measured best on the corpus's validation split for phone input, named
    from engine.synthesis.method_choice import choose_methods

    best = choose_methods(small_manifold)["best"]["phones"]  # cached by the synthesis above
    assert f"method: {best}, best on validation (phones protocol: RMSE X" in text
    assert f"{best}: 35 frames" in text and "wrote 35 OBJ files" in text
    rows = list(csv.reader(out.read_text().splitlines()))
    c = small_manifold.corpus_
    # rows and columns named for what they are (was "35 x 468 frames")
    assert f"wrote {out} (35 frames x {c.frames.shape[1]} values: x, y, z of {c.n_points} points)" in text
    assert rows[0][0] == "time" and len(rows[0]) == 1 + c.frames.shape[1]
    assert len(rows) == 1 + 35
    vals = np.array(rows[1:], dtype=float)
    np.testing.assert_allclose(np.diff(vals[:, 0]), 1 / 60, atol=1e-6)
    objs = sorted(meshes.glob("*.obj"))
    assert len(objs) == 35
    verts = [ln for ln in objs[0].read_text().splitlines() if ln.startswith("v ")]
    assert len(verts) == c.n_points


def test_utterance_npy_values_and_methods(mfile, small_manifold, tmp_path):
    u = small_manifold.corpus_.utterances[2]
    from app.cli.synthesize import METHODS
    from engine.synthesis.methods import METHODS as ENGINE_METHODS

    assert METHODS == ENGINE_METHODS
    Xo = small_manifold.Fx_[u.start:u.stop]
    from engine.phonetics.targets import targets_from_utterance

    f = targets_from_utterance(small_manifold, u.id, on_collision="merge").frames
    for method in METHODS:
        out = tmp_path / f"{method}.npy"
        assert main(["synthesize", "--manifold", str(mfile), "--utterance", u.id, "--method", method,
                     "--values", "fx", "-o", str(out), "-q"]) == 0
        X = np.load(out)
        assert X.shape == (u.n_frames, small_manifold.Fx_.shape[1]) and np.isfinite(X).all()
        if method in ("manifold", "sv-hermite", "linear", "cubic"):  # the oracle X at the targets is kept
            np.testing.assert_allclose(X[f], Xo[f], atol=1e-3 * np.abs(Xo).max())
    fy = tmp_path / "fy.npy"
    assert main(["synthesize", "--manifold", str(mfile), "--utterance", u.id, "--method", "viterbi",
                 "--values", "fy", "-o", str(fy)]) == 0
    assert np.load(fy).shape == (u.n_frames, 3)


def test_text_and_textgrid_inputs_with_ply(mfile, tmp_path, capsys):
    assert main(["synthesize", "--manifold", str(mfile), "--text", "a map", "--mesh-dir", str(tmp_path / "m"),
                 "--mesh-format", "ply"]) == 0
    assert sorted((tmp_path / "m").glob("*.ply"))
    tg = tmp_path / "x.TextGrid"
    tg.write_text(
        'File type = "ooTextFile"\nObject class = "TextGrid"\n\nxmin = 0\nxmax = 0.3\ntiers? <exists>\nsize = 1\n'
        'item []:\n    item [1]:\n        class = "IntervalTier"\n        name = "phones"\n        xmin = 0\n'
        '        xmax = 0.3\n        intervals: size = 2\n        intervals [1]:\n            xmin = 0\n'
        '            xmax = 0.1\n            text = "F"\n        intervals [2]:\n            xmin = 0.1\n'
        '            xmax = 0.3\n            text = "IY1"\n', encoding="utf-8")
    capsys.readouterr()
    assert main(["synthesize", "--manifold", str(mfile), "--textgrid", str(tg), "--method", "linear"]) == 0
    assert "linear: 18 frames" in capsys.readouterr().out


def test_bad_inputs_fail_cleanly(mfile, tmp_path, capsys):
    assert main(["synthesize", "--manifold", str(mfile), "--phones", "p 0.1 qx 0.1",
                 "-o", str(tmp_path / "a.csv")]) == 2
    err = capsys.readouterr().err
    assert "'qx'" in err and "known phones" in err
    assert not (tmp_path / "a.csv").exists()
    assert main(["synthesize", "--manifold", str(mfile), "--phones", "p 0.1 aa", "-o", str(tmp_path / "a.csv")]) == 2
    assert "label/duration pairs" in capsys.readouterr().err
    assert main(["synthesize", "--manifold", str(mfile), "--utterance", "nope"]) == 2
    assert "no utterance 'nope'" in capsys.readouterr().err
    assert main(["synthesize", "--manifold", str(mfile), "--phones", "p 0.1", "-o", str(tmp_path / "a.txt")]) == 2
    assert "must end in .csv or .npy" in capsys.readouterr().err
    assert main(["synthesize", "--manifold", str(mfile), "--phones", "p 0.1", "--method", "linear",
                 "--values", "fy", "-o", str(tmp_path / "a.npy")]) == 2
    assert "--values fy needs --method viterbi" in capsys.readouterr().err
    assert main(["synthesize", "--manifold", str(mfile), "--textgrid", str(tmp_path / "none.TextGrid")]) == 2
    assert "no such TextGrid" in capsys.readouterr().err
    assert main(["synthesize", "--manifold", str(tmp_path / "missing.npz"), "--phones", "p 0.1"]) == 2


def test_best_method_follows_the_targets_and_is_named(mfile, small_manifold, capsys):
    """Oracle targets (an utterance) and phone-only targets are different protocols: each gets the method its
    protocol measured best on validation, and the output says which and why."""
    from engine.synthesis.method_choice import choose_methods

    choice = choose_methods(small_manifold)
    u = small_manifold.corpus_.utterances[3]
    assert main(["synthesize", "--manifold", str(mfile), "--utterance", u.id, "-q"]) == 0
    out = capsys.readouterr().out
    best = choice["best"]["oracle"]
    assert f"method: {best}, best on validation (oracle protocol: RMSE X" in out
    assert out.splitlines()[-1].startswith(f"{best}: {u.n_frames} frames")
    # validation numbers quoted are the cached ones
    assert f"RMSE X {choice['method_validation']['oracle'][best]['rmse_x']:.4g}" in out


def test_the_retired_per_method_table_says_where_its_methods_went(small_corpus, tmp_path, capsys):
    ids = [u.id for u in small_corpus.utterances]
    path = small_corpus.subset(ids[:7]).save(tmp_path / "c.npz")
    csv_out = tmp_path / "table.csv"
    assert main(["evaluate", str(path), "--methods", "cubic,unitselection,magic", "-q", "--csv", str(csv_out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert "--methods belonged to the older per-method table" in err and "without it" in err
    assert "cubic -> oracle/pchip; unitselection -> phones/unitselection; magic -> no such method" in err
    assert not csv_out.exists()
    assert main(["evaluate", str(path), "--inverse-dims", "3", "-q"]) == 2
    err = capsys.readouterr().err
    assert "--inverse-dims belonged to the older per-method table" in err and "linear-phones -> phones/linear" in err


def test_inverse_choice_reaches_the_synthesiser(mfile, small_manifold, tmp_path):
    """--inverse / --smoothing pick the Y -> X map: the state-mean path's X is exactly the states' mean X."""
    from app.cli.synthesize import INVERSES as CLI_INVERSES
    from engine.synthesis.viterbi import INVERSES

    assert CLI_INVERSES == INVERSES
    u = small_manifold.corpus_.utterances[1]
    outs = {}
    for inverse in INVERSES:
        out = tmp_path / f"{inverse}.npy"
        assert main(["synthesize", "--manifold", str(mfile), "--utterance", u.id, "--method", "viterbi",
                     "--inverse", inverse, "--values", "fx", "-o", str(out), "-q"]) == 0
        outs[inverse] = np.load(out)
        assert outs[inverse].shape == (u.n_frames, small_manifold.Fx_.shape[1])
    # every row of the state-mean trajectory is one state's mean F^x
    lab = np.asarray(small_manifold.states_.labels_)
    means = np.stack([small_manifold.Fx_[lab == k].mean(axis=0) for k in np.unique(lab)])
    d = np.abs(outs["state-mean"][:, None, :] - means[None, :, :]).max(axis=2).min(axis=1)
    assert d.max() < 1e-4 * np.abs(means).max()
    assert not np.allclose(outs["state-mean"], outs["delaunay"])
    smooth = tmp_path / "smooth.npy"
    assert main(["synthesize", "--manifold", str(mfile), "--utterance", u.id, "--method", "viterbi",
                 "--inverse", "state-mean", "--smoothing", "2", "--values", "fx", "-o", str(smooth), "-q"]) == 0
    assert np.abs(np.diff(np.load(smooth), axis=0)).max() < np.abs(np.diff(outs["state-mean"], axis=0)).max()
