"""``lipspace synthesize --textgrid IN --praat OUT.TextGrid``: the synthesis on the input's clock, for Praat."""
from __future__ import annotations

import numpy as np
import pytest

from app.cli import main


def _input(path):
    """A TextGrid laid out as Praat writes them: a word tier first, silence before the first phone (0.25 s)."""
    from engine.io.writers.praat import IntervalTier, write_textgrid

    return write_textgrid(path, 0, 1.5, [IntervalTier("words", [(0, 1.5, "bob")]), IntervalTier(
        "phones", [(0.25, 0.35, "B"), (0.35, 0.65, "AA1"), (0.65, 0.75, "B")])])


@pytest.fixture(scope="module")
def mfile(small_manifold, tmp_path_factory):
    return small_manifold.save(tmp_path_factory.mktemp("synth_praat") / "m.npz")


def test_the_textgrid_and_csv_line_up_with_the_input(mfile, tmp_path, capsys):
    pd = pytest.importorskip("pandas")
    from engine.io import read_textgrid
    from engine.io.readers.alignment import _parse_textgrid

    src = _input(tmp_path / "in.TextGrid")
    out = tmp_path / "out.TextGrid"
    # the paper's path: its trajectory has states, so the CSV has a state column
    assert main(["synthesize", "--manifold", str(mfile), "--textgrid", str(src), "--method", "viterbi",
                 "--praat", str(out)]) == 0
    assert "as the input" in capsys.readouterr().out
    g = _parse_textgrid(out)
    assert (g.xmin, g.xmax) == (0.0, 1.5) and g.names() == ["phones", "targets", "landmarks"]
    assert read_textgrid(out, tier="phones") == read_textgrid(src)  # the phone tier as read, same times
    d = pd.read_csv(tmp_path / "out.csv")
    assert list(d.columns) == ["time_s", "frame", "phone", "target", "lip_aperture", "state"]
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


def test_praat_opens_it_with_the_input_span_and_the_targets(mfile, tmp_path, praat):
    src = _input(tmp_path / "in.TextGrid")
    out = tmp_path / "out.TextGrid"
    # the paper's path: its trajectory has states, so the CSV has a state column
    assert main(["synthesize", "--manifold", str(mfile), "--textgrid", str(src), "--method", "viterbi",
                 "--praat", str(out)]) == 0
    got = praat('form C\n  sentence f x\nendform\nRead from file: f$\nn = Get number of points: 2\n'
                'a = Get start time\nb = Get end time\nt = Get time of point: 2, 2\nlab$ = Get label of point: 2, 2\n'
                'writeInfoLine: n, " ", a, " ", b, " ", fixed$ (t, 6), " ", lab$\n', out).split()
    assert got[:3] == ["3", "0", "1.5"] and float(got[3]) == pytest.approx(0.5, abs=1 / 60) and got[4] == "aa"


def test_praat_outputs_are_never_replaced_without_force(mfile, tmp_path, capsys):
    src = _input(tmp_path / "in.TextGrid")
    (tmp_path / "out.csv").write_text("mine")
    args = ["synthesize", "--manifold", str(mfile), "--textgrid", str(src), "--praat", str(tmp_path / "out.TextGrid")]
    assert main(args) == 2
    assert "out.csv (--praat) already exists" in capsys.readouterr().err and not (tmp_path / "out.TextGrid").exists()
    assert main(args + ["--force"]) == 0 and (tmp_path / "out.csv").read_text().startswith("time_s,")
    assert main(args[:-1] + [str(tmp_path / "new.csv")]) == 2 and "OUT.TextGrid" in capsys.readouterr().err


def test_a_real_recording_synthesised_from_its_own_labels_keeps_their_clock(mocha_manifold, shared_data, tmp_path):
    import warnings

    pd = pytest.importorskip("pandas")
    from engine.io import read_alignment
    from engine.phonetics.targets import targets_from_textgrid
    from engine.synthesis.methods import make_synthesizer
    from engine.synthesis.tiers import input_timeline, synthesis_outputs

    m = mocha_manifold
    mfile = m.save(tmp_path / "mocha.npz")
    out = tmp_path / "fsew0.TextGrid"
    lab = shared_data / "mocha-fsew0" / "fsew0_001.lab"
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
