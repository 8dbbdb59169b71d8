"""``lipspace figures``: the figure set in batch, no display."""
from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from app.cli import main
from app.figures import FIGURES


@pytest.fixture(scope="module")
def manifold_file(small_manifold, tmp_path_factory):
    return small_manifold.save(tmp_path_factory.mktemp("fig") / "m.npz")


def test_renders_the_whole_set(manifold_file, tmp_path, capsys):
    out = tmp_path / "figs"
    assert main(["figures", str(manifold_file), "-o", str(out), "--dpi", "50", "-q"]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(f"{n}.png" for n in FIGURES)
    for p in out.iterdir():
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"{len(FIGURES)}/{len(FIGURES)} figures" in capsys.readouterr().out


def test_only_and_several_formats(manifold_file, tmp_path, small_manifold):
    uid = small_manifold.corpus_.utterances[2].id
    assert main(["figures", str(manifold_file), "-o", str(tmp_path), "--only", "fig1b,fig3",
                 "--format", "svg", "--format", "pdf", "--utterance", uid, "-q"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig1b.pdf", "fig1b.svg", "fig3.pdf", "fig3.svg"]
    assert ET.fromstring((tmp_path / "fig3.svg").read_bytes()).tag.endswith("svg")
    assert (tmp_path / "fig1b.pdf").read_bytes().startswith(b"%PDF")
    # the chosen utterance is the one fig 3 regenerates (its id is in the title text)
    assert uid in (tmp_path / "fig3.svg").read_text()


def test_without_a_file_builds_on_the_synthetic_talker(tmp_path, capsys):
    out = tmp_path / "figs"
    assert main(["figures", "--preset", "small", "-o", str(out), "--only", "fig2c", "-q"]) == 0
    assert [p.name for p in out.iterdir()] == ["fig2c.png"]


def test_corpus_file_is_fitted_first(tmp_path, capsys):
    import numpy as np

    from engine.recordings.corpus import Corpus, Utterance

    # a corpus too short to fit: the command must try to fit it (not read it as a manifold)
    c = Corpus(np.zeros((8, 6), np.float32), 60.0, [Utterance("u", 0, 8)], name="tiny")
    p = c.save(tmp_path / "c.npz")
    assert main(["figures", str(p), "-o", str(tmp_path / "figs"), "-q"]) == 2
    assert "too few to build a manifold" in capsys.readouterr().err
    assert not (tmp_path / "figs").exists()


def test_user_errors_are_clean(manifold_file, tmp_path, capsys):
    out = tmp_path / "figs"
    assert main(["figures", str(manifold_file), "-o", str(out), "--only", "fig9", "-q"]) == 2
    assert "fig9" in capsys.readouterr().err
    assert main(["figures", str(manifold_file), "-o", str(out), "--utterance", "nope", "-q"]) == 2
    assert "no such utterance" in capsys.readouterr().err
    assert main(["figures", str(tmp_path / "missing.npz"), "-o", str(out), "-q"]) == 2
    assert "no such file" in capsys.readouterr().err
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["figures", str(manifold_file), "-o", str(blocker), "-q"]) == 2
    assert "not a directory" in capsys.readouterr().err
    assert not out.exists()
