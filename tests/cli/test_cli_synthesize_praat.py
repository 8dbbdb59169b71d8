"""``lipspace synthesize --textgrid IN --praat OUT.TextGrid``: the synthesis on the input's clock, for Praat."""
from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

from app.cli import main

PRAAT = shutil.which("praat")

#: a TextGrid as Praat writes it: a word tier first, silence before the first phone (starts at 0.25 s)
INPUT = '''File type = "ooTextFile"
Object class = "TextGrid"

xmin = 0
xmax = 1.5
tiers? <exists>
size = 2
item []:
    item [1]:
        class = "IntervalTier"
        name = "words"
        xmin = 0
        xmax = 1.5
        intervals: size = 1
        intervals [1]:
            xmin = 0
            xmax = 1.5
            text = "bob"
    item [2]:
        class = "IntervalTier"
        name = "phones"
        xmin = 0
        xmax = 1.5
        intervals: size = 5
        intervals [1]:
            xmin = 0
            xmax = 0.25
            text = ""
        intervals [2]:
            xmin = 0.25
            xmax = 0.35
            text = "B"
        intervals [3]:
            xmin = 0.35
            xmax = 0.65
            text = "AA1"
        intervals [4]:
            xmin = 0.65
            xmax = 0.75
            text = "B"
        intervals [5]:
            xmin = 0.75
            xmax = 1.5
            text = ""
'''


@pytest.fixture(scope="module")
def mfile(small_manifold, tmp_path_factory):
    return small_manifold.save(tmp_path_factory.mktemp("synth_praat") / "m.npz")


def test_the_textgrid_and_csv_line_up_with_the_input(mfile, tmp_path, capsys):
    pd = pytest.importorskip("pandas")
    from engine.io import read_textgrid
    from engine.io.alignment import _parse_textgrid

    src = tmp_path / "in.TextGrid"
    src.write_text(INPUT, encoding="utf-8")
    out = tmp_path / "out.TextGrid"
    assert main(["synthesize", "--manifold", str(mfile), "--textgrid", str(src), "--praat", str(out)]) == 0
    assert "as the input" in capsys.readouterr().out
    g = _parse_textgrid(out)
    assert (g.xmin, g.xmax) == (0.0, 1.5) and list(g) == ["phones", "targets", "landmarks"]
    assert read_textgrid(out, tier="phones") == read_textgrid(src)  # the phone tier as read, same times
    d = pd.read_csv(tmp_path / "out.csv")
    assert list(d.columns) == ["time_s", "frame", "phone", "target", "opening_fx1", "state"]
    # on the input's clock: the synthesis starts at the first phone (0.25 s) and steps at the corpus rate
    assert d["time_s"].iloc[0] == pytest.approx(0.25) and np.allclose(np.diff(d["time_s"]), 1 / 60, atol=1e-6)
    for t, ph in zip(d["time_s"], d["phone"]):
        want = next(p.label for p in read_textgrid(src) if p.start <= t + 1e-9 < p.end)
        assert ph == want
    tg = d.dropna(subset=["target"])
    assert len(tg) == len(g["targets"]) == 3
    np.testing.assert_allclose([p.xpos for p in g["targets"]], tg["time_s"], atol=1e-6)
    assert [p.text for p in g["targets"]] == list(tg["target"]) == ["b", "aa", "b"]
    # the targets sit at the phones' middles of the input
    np.testing.assert_allclose(tg["time_s"], [0.3, 0.5, 0.7], atol=1 / 60)
    assert (tmp_path / "out.csv.json").exists()
    if PRAAT:
        script = tmp_path / "c.praat"
        script.write_text('form C\n  sentence f x\nendform\nRead from file: f$\nn = Get number of points: 2\n'
                          'a = Get start time\nb = Get end time\nt = Get time of point: 2, 2\n'
                          'writeInfoLine: n, " ", a, " ", b, " ", fixed$ (t, 6)\n', encoding="utf-8")
        r = subprocess.run([PRAAT, "--run", str(script), str(out)], capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        n, a, b, t = r.stdout.split()
        assert (int(n), float(a), float(b)) == (3, 0.0, 1.5) and float(t) == pytest.approx(tg["time_s"].iloc[1])


def test_praat_outputs_are_never_replaced_without_force(mfile, tmp_path, capsys):
    src = tmp_path / "in.TextGrid"
    src.write_text(INPUT, encoding="utf-8")
    (tmp_path / "out.csv").write_text("mine")
    args = ["synthesize", "--manifold", str(mfile), "--textgrid", str(src), "--praat", str(tmp_path / "out.TextGrid")]
    assert main(args) == 2
    assert "out.csv exists already" in capsys.readouterr().err and not (tmp_path / "out.TextGrid").exists()
    assert main(args + ["--force"]) == 0 and (tmp_path / "out.csv").read_text().startswith("time_s,")
    assert main(args[:-1] + [str(tmp_path / "out.csv")]) == 2 and "OUT.TextGrid" in capsys.readouterr().err


def test_a_real_recording_synthesised_from_its_own_labels_keeps_their_clock(shared_data, tmp_path):
    import warnings

    pd = pytest.importorskip("pandas")
    from engine.io import read_alignment, read_corpus, resample
    from engine.manifold import Manifold
    from engine.synthesis import make_synthesizer
    from engine.synthesis_tiers import input_timeline, synthesis_outputs
    from engine.targets import targets_from_textgrid

    d = shared_data / "mocha-fsew0"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a 2-s, 116-frame corpus: the data warnings are expected
        corpus = resample(read_corpus(d / "fsew0_001.ema", alignment=d / "fsew0_001.lab"), 60.0)
        m = Manifold().fit(corpus)
    mfile = m.save(tmp_path / "mocha.npz")
    out = tmp_path / "fsew0.TextGrid"
    lab = d / "fsew0_001.lab"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["synthesize", "--manifold", str(mfile), "--textgrid", str(lab), "--method", "linear",
                     "--praat", str(out)]) == 0
        traj = make_synthesizer("linear", m).synthesize(tg := targets_from_textgrid(m, lab))
    f = pd.read_csv(tmp_path / "fsew0.csv")
    assert "lip_aperture" in f.columns  # MOCHA names its lip sensors: the synthesised frames' aperture
    table, (xmin, xmax, _tiers) = synthesis_outputs(m, tg, traj, timeline=input_timeline(lab))
    np.testing.assert_allclose(f["lip_aperture"], table.columns["lip_aperture"], rtol=1e-6)
    assert (f["lip_aperture"] > 0).all()
    phones = read_alignment(lab)
    assert f["time_s"].iloc[0] == pytest.approx(phones[0].start) and xmax == pytest.approx(phones[-1].end)
