"""Real-recording faults end to end: a generated 3-speaker articulograph corpus (7 sensors x 6 values, 250 Hz,
CSV without names, speaker origins 100 mm apart, offsets between utterances, head motion, tongue sensors, no
phone labels) through import -> build -> info / clusters / synthesize / evaluate / figures."""
import contextlib
import io
import re

import numpy as np
import pytest

from app.cli import main
from engine.recordings.corpus import Corpus
from engine.talker.multispeaker import generate_recordings


def _run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    d = tmp_path_factory.mktemp("ema")
    files = []
    for r in generate_recordings(n_speakers=3, n_utterances=3, duration_s=(2.0, 2.5), seed=5):
        (d / r.speaker).mkdir(exist_ok=True)
        f = d / r.speaker / f"{r.id}.csv"
        np.savetxt(f, r.matrix, delimiter=",", fmt="%.4f")
        files.append(str(f))
    return d, files


@pytest.fixture(scope="module")
def good(recordings):
    """Imported as documented: layout, speakers from the directories; default registration and 60 Hz."""
    d, files = recordings
    corpus, mfile = d / "good.npz", d / "good-m.npz"
    rc, out, err = _run(["import", *files, "--layout", "ema7x6", "--rate", "250", "--speaker-from", "dir",
                         "-o", str(corpus)])
    assert rc == 0, err
    rc, out, berr = _run(["build", str(corpus), "-o", str(mfile), "--states", "30", "-q"])
    assert rc == 0, berr
    return corpus, mfile, err, berr


@pytest.fixture(scope="module")
def naive(recordings):
    """Every sensor (tongue too), no registration, no speakers, no speaker normalisation."""
    d, files = recordings
    corpus, mfile = d / "naive.npz", d / "naive-m.npz"
    assert _run(["import", *files, "--layout", "ema7x6", "--rate", "250", "--points", "all", "--register", "none",
                 "-o", str(corpus)])[0] == 0
    rc, out, berr = _run(["build", str(corpus), "-o", str(mfile), "--states", "30", "-q", "--speaker-norm", "none"])
    assert rc == 0, berr
    return corpus, mfile, berr


def test_import_says_what_it_did(good):
    corpus, _, err, _ = good
    c = Corpus.load(corpus)
    assert c.rate == 60 and c.point_names == ["UL", "LL", "LC", "RC"] and c.speakers == ["S1", "S2", "S3"]
    assert "resampled 250 -> 60 Hz (polyphase x6/25, Kaiser-windowed anti-aliasing FIR)" in err
    assert "registration: utterance centring (no reference sensors)" in err


def test_registered_build_is_connected_and_opening_follows_the_aperture(good):
    _, mfile, _, berr = good
    assert "splits" not in berr and "Traceback" not in berr
    rc, out, err = _run(["info", str(mfile)])
    assert rc == 0
    assert "opening     defined by lip aperture" in out
    opening, accelerating = class_agreement_from_info(out)
    assert opening >= 95.0 and accelerating >= 85.0, out
    assert "warning" not in err
    assert "speakers    3: S1, S2, S3" in out and "speaker normalisation mean over 3 speakers" in out


def test_naive_build_names_the_causes(naive):
    _, mfile, berr = naive
    assert "splits into" in berr and "along recordings" in berr and "--register utterance" in berr
    rc, out, err = _run(["info", str(mfile)])
    assert rc == 0
    assert "the tangent classes agree with the lip aperture less than expected" in err
    assert "3 tongue sensors in the shape space" in err and "no registration" in err


def test_unlabelled_clusters_synthesis_and_figures(good, tmp_path):
    corpus, mfile, _, _ = good
    rc, out, err = _run(["clusters", str(mfile), "-q"])
    assert rc == 0, err
    assert "kinematic landmarks" in err
    rows = {ln.split()[0]: ln.split() for ln in out.splitlines()[3:] if ln.strip()}
    assert set(rows) == {"open", "closed", "opening", "closing"}
    assert float(rows["opening"][5]) > 0.9 and float(rows["closing"][5]) < 0.1  # side of the zero-velocity plane
    rc, _, err = _run(["clusters", str(mfile), "--labels", "phones", "-q"])
    assert rc == 2 and "--labels kinematic" in err
    uid = Corpus.load(corpus).utterances[0].id
    rc, out, err = _run(["synthesize", "--manifold", str(mfile), "--utterance", uid, "-o", str(tmp_path / "a.npy"),
                         "-q"])
    assert rc == 0 and "(kinematic landmarks: it has no phone alignment)" in out, out + err
    rc, out, err = _run(["synthesize", "--manifold", str(mfile), "--utterance", uid, "--key-frames", "kinematic",
                         "-q"])
    assert rc == 0, err
    rc, out, err = _run(["synthesize", "--manifold", str(mfile), "--phones", "p 0.1 aa 0.1", "-q"])
    assert rc == 2 and "has no phone labels" in err and "--states S,S,..." in err
    rc, out, err = _run(["synthesize", "--manifold", str(mfile), "--states", "0,5,9", "-o", str(tmp_path / "b.npy"),
                         "-q"])
    assert rc == 0 and np.load(tmp_path / "b.npy").shape[0] == 2 * 12 + 1
    rc, out, err = _run(["synthesize", "--manifold", str(mfile), "--states", "0,5", "--key-frames", "3", "-q"])
    assert rc == 2 and "give --utterance ID too" in err
    rc, out, err = _run(["figures", str(mfile), "-o", str(tmp_path / "f"), "--only", "fig3,fig4", "-q"])
    assert rc == 0, err
    assert "fig4 skipped: it needs the phone labels /b/ /p/ /m/" in err
    assert (tmp_path / "f" / "fig3.png").is_file() and not (tmp_path / "f" / "fig4.png").exists()


def test_evaluate_unlabelled(good):
    corpus, _, _, _ = good
    rc, out, err = _run(["evaluate", str(corpus), "-q"])
    assert rc == 0, err
    assert "kinematic landmarks" in err and "linear" in out


def test_head_sensors_give_rigid_registration(tmp_path):
    from engine.talker.multispeaker import layout_text

    (tmp_path / "ref.layout").write_text(layout_text(reference=True))
    files = []
    for r in generate_recordings(n_speakers=2, n_utterances=2, duration_s=(2.0, 2.0), head_motion=3.0,
                                 reference=True, seed=7):
        f = tmp_path / f"{r.id}.npy"
        np.save(f, r.matrix)
        files.append(str(f))
    corpus, mfile = tmp_path / "c.npz", tmp_path / "m.npz"
    rc, out, err = _run(["import", *files, "--layout", str(tmp_path / "ref.layout"), "--rate", "250",
                         "--speaker-from", "prefix", "-o", str(corpus)])
    assert rc == 0, err
    assert "registration: rigid (Procrustes) to reference sensors NOSE, LMA, RMA" in err
    c = Corpus.load(corpus)
    assert c.point_names == ["UL", "LL", "LC", "RC"] and c.speakers == ["S1", "S2"]
    rc, out, err = _run(["build", str(corpus), "-o", str(mfile), "--states", "12", "-q"])
    assert rc == 0 and "warning" not in err, err
    rc, out, err = _run(["info", str(mfile)])
    opening, accelerating = class_agreement_from_info(out)
    assert opening >= 95.0 and accelerating >= 85.0, out


def test_plain_matrix_errors_point_at_layouts(tmp_path, recordings):
    import scipy.io

    _, files = recordings
    M = np.loadtxt(files[0], delimiter=",")
    scipy.io.savemat(tmp_path / "X.mat", {"X": M})
    for cmd in (["import", str(tmp_path / "X.mat"), "-o", str(tmp_path / "x.npz")],
                ["build", str(tmp_path / "X.mat"), "-o", str(tmp_path / "m.npz"), "-q"]):
        rc, out, err = _run(cmd)
        assert rc == 2 and "plain" in err and "--layout ema7x6" in err, err
    rc, out, err = _run(["import", str(tmp_path / "X.mat"), "--layout", "ema7x6", "-o", str(tmp_path / "x.npz")])
    assert rc == 2 and "--rate HZ" in err
    rc, out, err = _run(["import", str(tmp_path / "X.mat"), "--layout", "ema7x7", "--rate", "250",
                         "-o", str(tmp_path / "x.npz")])
    assert rc == 2 and "42 columns but layout 'ema7x7' expects 7 sensors x 7 values = 49" in err
    assert "42 = 6 sensors x 7 values or 7 sensors x 6 values: give a layout with that shape, e.g. ema7x6" in err
    assert not (tmp_path / "x.npz").exists()


def test_evaluate_protocols_exit_status_when_every_item_fails(good, tmp_path):
    corpus, _, _, _ = good
    from dataclasses import replace

    from engine.recordings.kinematics import with_kinematic_labels

    c = with_kinematic_labels(Corpus.load(corpus))
    c = c.subset([u.id for u in c.utterances[:3]])  # small: 2 training utterances, no validation split
    bare = c.utterances[0].id
    c = replace(c, utterances=[replace(u, phones=()) if u.id == bare else u for u in c.utterances],
                point_roles=None, point_names=[f"p{i}" for i in range(c.n_points)])
    c.save(tmp_path / "part.npz")
    rc, out, err = _run(["evaluate", str(tmp_path / "part.npz"), "--test-ids", bare, "-q"])
    assert rc == 1, out + err
    assert "every item failed" in err


def test_roles_mark_a_mesh_s_lip_points(tmp_path):
    from engine.io import write_mesh_sequence

    r = generate_recordings(n_speakers=1, n_utterances=1, duration_s=(3.0, 3.0), head_motion=0.0, seed=9)[0]
    P = r.matrix.reshape(len(r.matrix), 7, 6)[::4, :4, :3]  # UL LL LC RC at 62.5 Hz, as mesh vertices 0-3
    write_mesh_sequence(tmp_path / "mesh", P, faces=[[0, 2, 1], [0, 1, 3]], format="ply")
    corpus, mfile = tmp_path / "c.npz", tmp_path / "m.npz"
    rc, out, err = _run(["import", str(tmp_path / "mesh"), "--rate", "62.5", "-o", str(corpus),
                         "--roles", "upper_lip=0;lower_lip=1;left_corner=2;right_corner=3"])
    assert rc == 0, err
    c = Corpus.load(corpus)
    assert c.point_roles == ["upper_lip", "lower_lip", "left_corner", "right_corner"] and c.rate == 60
    rc, out, err = _run(["build", str(corpus), "-o", str(mfile), "--states", "8", "-q"])
    assert rc == 0, err
    rc, out, err = _run(["info", str(mfile)])
    assert "opening     defined by lip aperture" in out
    rc, out, err = _run(["import", str(tmp_path / "mesh"), "--rate", "62.5", "-o", str(corpus), "--force",
                         "--roles", "upper_lip=7"])
    assert rc == 2 and "no point '7'; expected an index 0..3" in err


@pytest.mark.parametrize("fmt", ["obj", "ply"])
def test_mesh_export_labels_the_sensors(good, tmp_path, fmt):
    from engine.io import read_mesh, read_vertex_labels

    _, mfile, _, _ = good
    out, mesh = tmp_path / "frames.npy", tmp_path / "mesh"
    rc, so, err = _run(["synthesize", "--manifold", str(mfile), "--states", "0,5,9", "-o", str(out),
                        "--mesh-dir", str(mesh), "--mesh-format", fmt, "-q"])
    assert rc == 0, err
    assert "then the 4 labelled sensors" in so
    frames = np.load(out).reshape(-1, 4, 3)  # UL LL LC RC
    files = sorted(mesh.glob(f"frame_*.{fmt}"))
    assert len(files) == len(frames)
    order = {"UL": 0, "LL": 1, "LC": 2, "RC": 3}
    for k in (0, len(files) // 2, len(files) - 1):
        V, F = read_mesh(files[k])
        labels = read_vertex_labels(files[k])
        assert sorted(n for n, _ in labels) == sorted(order) and F.max() < min(v for _, v in labels)
        for name, v in labels:
            np.testing.assert_allclose(V[v], frames[k, order[name]], rtol=1e-5, atol=1e-4)


def class_agreement_from_info(out):
    """(opening %, accelerating %) from ``lipspace info``'s "classes vs" line."""
    line = next(x for x in out.splitlines() if x.startswith("classes vs"))
    return (float(re.search(r"opening ([\d.]+)%", line).group(1)),
            float(re.search(r"accelerating ([\d.]+)%", line).group(1)))
