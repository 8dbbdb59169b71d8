"""The whole pipeline on real data: the Haskins IEEE pair, import -> build -> clusters -> synthesize."""
import contextlib
import csv
import io
import re

import numpy as np
import pytest

from app.cli import main
from engine.manifold.model import Manifold
from engine.recordings.corpus import Corpus


@pytest.fixture(scope="module")
def haskins_files(shared_data):
    files = sorted(str(p) for p in (shared_data / "haskins-ieee").glob("*.mat"))
    if len(files) < 2:
        pytest.skip("the Haskins IEEE pair is not in ../shared/data/haskins-ieee")
    return files


@pytest.fixture(scope="module")
def built(haskins_files, tmp_path_factory):
    d = tmp_path_factory.mktemp("haskins")
    corpus, mfile = d / "haskins.npz", d / "haskins-manifold.npz"
    assert main(["import", *haskins_files, "-o", str(corpus)]) == 0
    # two utterances of ~2-3 s at 100 Hz: a few dozen states
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        assert main(["build", str(corpus), "-o", str(mfile), "--states", "24", "-q"]) == 0
    return corpus, mfile, err.getvalue()


def test_build_fits_a_manifold_on_the_real_pair(built, capsys):
    corpus, mfile, err = built
    # two speakers, one sentence each: their states do not connect, and build says so in one line
    assert "lipspace build: warning: the state graph is not strongly connected" in err
    assert "Traceback" not in err and "StateGraphConnectivityWarning" not in err
    c = Corpus.load(corpus)
    m = Manifold.load(mfile)
    # imported at the 60 Hz analysis rate (from 100 Hz), each utterance centred (no reference sensors)
    assert c.rate == pytest.approx(60.0) and len(c.utterances) == 2 and c.dims == 3
    assert c.registration.startswith("utterance centring") and c.point_roles[:2] == ["upper_lip", "lower_lip"]
    assert m.Fy_.shape[0] == c.frames.shape[0] and np.isfinite(m.Fy_).all()
    assert m.states_.centroids_.shape[0] == 24
    # every frame's projection reproduces its embedding (the file round-trips the fit)
    np.testing.assert_allclose(m.project(c.frames[:50], bounds=np.array([[0, 50]]))[:, :3],
                               m.Fy_[:50, :3], atol=1e-3 * float(np.abs(m.Fy_[:, :3]).max()))
    assert main(["info", str(mfile)]) == 0
    out = capsys.readouterr().out
    assert "states" in out.lower()
    # "opening" is the lips parting: the tangent classes follow the UL-LL aperture
    assert "opening     defined by lip aperture" in out
    opening, accelerating = class_agreement_from_info(out)
    assert opening >= 95.0 and accelerating >= 85.0, out


def test_clusters_table_on_the_real_pair(built, tmp_path, capsys):
    _, mfile, _ = built
    out = tmp_path / "clusters.csv"
    assert main(["clusters", str(mfile), "--csv", str(out), "--min-count", "2", "-q"]) == 0
    rows = list(csv.DictReader(out.read_text().splitlines()))
    c = Manifold.load(mfile).corpus_
    labels = {p.label for u in c.utterances for p in u.phones}
    assert len(rows) >= 5
    for r in rows:
        assert int(r["count"]) >= 2 and 0.0 <= float(r["opening_fraction"]) <= 1.0
        assert r["phone"] in labels
    assert capsys.readouterr().out.strip()


def test_synthesize_a_real_utterance_and_a_phone_string(built, tmp_path, capsys):
    _, mfile, _ = built
    m = Manifold.load(mfile)
    u = m.corpus_.utterances[0]
    out = tmp_path / "utt.npy"
    assert main(["synthesize", "--manifold", str(mfile), "--utterance", u.id, "--values", "frames",
                 "-o", str(out), "-q"]) == 0
    F = np.load(out)
    assert F.shape == (u.n_frames, m.corpus_.frames.shape[1]) and np.isfinite(F).all()
    # synthetic lips stay inside the speaker's range of motion (the inverse map interpolates frames)
    lo, hi = m.corpus_.frames.min(0), m.corpus_.frames.max(0)
    span = hi - lo
    assert np.all(F >= lo - 0.05 * span) and np.all(F <= hi + 0.05 * span)
    labels = [p.label for p in u.phones if p.label.lower() not in ("sil", "sp", "")][:4]
    phones = " ".join(f"{lab} 0.1" for lab in labels)
    out2 = tmp_path / "phones.csv"
    assert main(["synthesize", "--manifold", str(mfile), "--phones", phones, "-o", str(out2), "-q"]) == 0
    rows = list(csv.reader(out2.read_text().splitlines()))
    assert rows[0][0] == "time" and len(rows) - 1 == round(0.4 * m.corpus_.rate)


def test_explorer_and_figures_open_a_foreign_file_directly(haskins_files, tmp_path):
    from app.files.source_loading import load_source, source_kind

    mat = haskins_files[0]
    assert source_kind(mat) == "foreign"
    m, src = load_source(mat, use_cache=False)
    # fitted as 'lipspace import' makes it: the 100-Hz file at the 60-Hz analysis rate (docs/DECISIONS.md, H10)
    assert src["kind"] == "foreign" and len(m.corpus_.utterances) == 1 and m.corpus_.rate == pytest.approx(60.0)
    assert any(h.startswith("resampled 100 -> 60 Hz") for h in m.corpus_.history)
    assert main(["figures", mat, "-o", str(tmp_path / "figs"), "--only", "scree", "-q"]) == 0
    assert [p.name for p in (tmp_path / "figs").glob("*.png")]
    lab = tmp_path / "x.lab"
    lab.write_text("0 0.1 sil\n")
    with pytest.raises(ValueError, match="phone alignment, not lip data"):
        source_kind(lab)


def class_agreement_from_info(out):
    """(opening %, accelerating %) from ``lipspace info``'s "classes vs" line."""
    line = next(x for x in out.splitlines() if x.startswith("classes vs"))
    return (float(re.search(r"opening ([\d.]+)%", line).group(1)),
            float(re.search(r"accelerating ([\d.]+)%", line).group(1)))
