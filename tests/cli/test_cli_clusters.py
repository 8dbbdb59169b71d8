"""``lipspace clusters``: the printed table, the CSV it writes, and its errors."""
import csv

import numpy as np
import pytest

from app.cli import main
from engine.manifold.clusters import PhoneClusters


@pytest.fixture(scope="module")
def manifold_file(small_manifold, tmp_path_factory):
    path = tmp_path_factory.mktemp("clusters") / "m.npz"
    small_manifold.save(path)
    return path


def test_table_and_csv_round_trip(manifold_file, small_manifold, tmp_path, capsys):
    out = tmp_path / "sub" / "clusters.csv"
    assert main(["clusters", str(manifold_file), "--csv", str(out)]) == 0
    text = capsys.readouterr().out
    pc = PhoneClusters().fit(small_manifold)
    assert f"{int(pc.counts_.sum())} phone mid-points in {len(pc.phones_)} clusters" in text
    header = text.splitlines()[next(i for i, line in enumerate(text.splitlines()) if line.startswith("phone"))]
    assert header.split()[:5] == ["phone", "count", "y1", "y2", "y3"]
    with open(out, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    want = pc.table()
    assert [r["phone"] for r in rows] == [w["phone"] for w in want]
    for r, w in zip(rows, want):
        assert int(r["count"]) == w["count"]
        assert r["nearest_y"] == w["nearest_y"] and r["nearest_x"] == w["nearest_x"]
        assert r["broad_class"] == w["broad_class"] and r["lipreading_class"] == w["lipreading_class"]
        for key in ("y1", "y2", "y3", "opening_fraction", "separation_y", "separation_x", "separation_nearest_x"):
            assert float(r[key]) == pytest.approx(w[key], rel=1e-5, abs=1e-9), key
    # every phone's printed row starts with its label and count
    for w in want:
        assert any(line.split()[:2] == [w["phone"], str(w["count"])] for line in text.splitlines())
    assert not list(out.parent.glob(".*part*"))  # written atomically, no temporary left


def test_selected_phones_print_separation_matrices(manifold_file, small_manifold, capsys):
    assert main(["clusters", str(manifold_file), "--phones", "m,p,b", "--dims", "2", "--measure", "dprime"]) == 0
    text = capsys.readouterr().out
    pc = PhoneClusters(n_dims=2).fit(small_manifold)
    rows = [line.split() for line in text.splitlines()]
    assert [r[0] for r in rows if r and r[0] in ("m", "p", "b") and len(r) > 5] == ["m", "p", "b"]
    assert "dprime separation in Y (shape + velocity):" in text and "dprime separation in X (shape only):" in text
    for space, title in (("y", "in Y"), ("x", "in X")):
        block = text.split(f"dprime separation {title}")[1].splitlines()[3:6]
        got = np.array([[float(v) for v in line.split()[1:]] for line in block])
        np.testing.assert_allclose(got, pc.separation_matrix(space, measure="dprime", phones=["m", "p", "b"]),
                                   atol=6e-4)


def test_corpus_input_fits_a_manifold(small_corpus, tmp_path, capsys):
    # a quarter of the small corpus keeps the manifold fit short
    corpus = small_corpus.subset([u.id for u in small_corpus.utterances[: len(small_corpus.utterances) // 4]])
    path = corpus.save(tmp_path / "c.npz")
    mids, labels = corpus.phone_table()[:2]
    names, counts = np.unique(labels[labels != "sil"], return_counts=True)
    top = [str(n) for n in names[np.argsort(-counts, kind="stable")[:2]]]
    out = tmp_path / "t.csv"
    assert main(["clusters", str(path), "--phones", ",".join(top), "--csv", str(out), "-q"]) == 0
    with open(out, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["phone"] for r in rows] == top
    assert [int(r["count"]) for r in rows] == [int(np.sum(labels == p)) for p in top]


def test_errors(manifold_file, tmp_path, capsys):
    assert main(["clusters", str(manifold_file), "--phones", "m,qq"]) == 2
    assert "no cluster for phone 'qq'" in capsys.readouterr().err
    assert main(["clusters", str(manifold_file), "--csv", str(tmp_path / "t.txt")]) == 2
    assert "must end in .csv" in capsys.readouterr().err
    assert main(["clusters", str(tmp_path / "missing.npz")]) == 2
    assert "no such" in capsys.readouterr().err
    assert main(["clusters", str(manifold_file), "--dims", "17"]) == 2
    assert "n_dims=17" in capsys.readouterr().err
    assert not (tmp_path / "t.txt").exists()
