"""Speakers of a lab's recordings on import: a regular-expression rule, folders as given, corpus files keeping
their speakers when joined, and warnings when a rule does not fit the names."""
import contextlib
import io
import os

import pytest

from app.cli import main
from engine.recordings.corpus import Corpus


def _run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, out.getvalue(), err.getvalue()


def _import(paths, out, *extra):
    return _run(["import", *map(str, paths), "--layout", "ema7x6", "-q", "--jobs", "1", "-o", str(out), *extra])


def test_a_regular_expression_names_the_speakers(lab_folder, tmp_path):
    _, paths = lab_folder
    rc, out, err = _import(paths, tmp_path / "c.npz", "--speaker-from", "re:^([A-Z]{3})")
    assert rc == 0, err
    c = Corpus.load(tmp_path / "c.npz")
    assert c.speakers == ["ABC", "KLM", "XYM"]
    assert [u.speaker for u in c.utterances] == [p.name[:3] for p in paths]
    assert "warning" not in err


def test_a_rule_that_makes_every_file_its_own_speaker_is_warned_about(lab_folder, tmp_path):
    _, paths = lab_folder
    rc, out, err = _import(paths, tmp_path / "c.npz", "--speaker-from", "prefix")
    assert rc == 0, err
    assert "warning: --speaker-from prefix made each of the 9 inputs its own speaker (the names have no '_')" in err
    assert "ABCFIA 3, KLMFIB 3, XYMNE 3 files" in err and "re:^([A-Za-z]+)" in err


def test_one_speaker_for_names_that_differ_is_warned_about(lab_folder, tmp_path):
    _, paths = lab_folder
    rc, out, err = _import(paths, tmp_path / "c.npz")
    assert rc == 0, err
    assert "warning: all 9 inputs are one unnamed speaker" in err and "3 different letter codes" in err
    # one name given on purpose: no warning
    rc, out, err = _import(paths, tmp_path / "d.npz", "--speaker", "lab")
    assert rc == 0 and "warning" not in err


def test_dir_names_the_folder_as_given_not_the_symlink_target(lab_folder, tmp_path):
    folder, paths = lab_folder
    links = []
    for code in ("ABC", "KLM", "XYM"):
        (tmp_path / code).mkdir()
        for p in paths:
            if p.name.startswith(code):
                os.symlink(p, tmp_path / code / p.name)
                links.append(tmp_path / code / p.name)
    linked_dir = tmp_path / "speaker1"
    os.symlink(folder, linked_dir)  # a symlinked folder: its own name, not 'matfiles'
    rc, _, err = _import(links, tmp_path / "c.npz", "--speaker-from", "dir")
    assert rc == 0, err
    assert Corpus.load(tmp_path / "c.npz").speakers == ["ABC", "KLM", "XYM"]
    rc, _, err = _import([linked_dir / paths[0].name], tmp_path / "d.npz", "--speaker-from", "dir")
    assert rc == 0, err
    assert Corpus.load(tmp_path / "d.npz").speakers == ["speaker1"]


def test_joining_corpus_files_keeps_each_one_a_speaker(lab_folder, tmp_path):
    _, paths = lab_folder
    parts = []
    for code in ("ABCFIA", "KLMFIB", "XYMNE"):
        out = tmp_path / f"{code}.npz"
        assert _import([p for p in paths if p.stem.startswith(code)], out, "--speaker", code)[0] == 0
        parts.append(out)
    rc, _, err = _run(["import", *map(str, parts), "-o", str(tmp_path / "pool.npz"), "-q"])
    assert rc == 0, err
    assert Corpus.load(tmp_path / "pool.npz").speakers == ["ABCFIA", "KLMFIB", "XYMNE"]
    nameless = []
    for code in ("ABCFIA", "KLMFIB"):
        out = tmp_path / f"n{code}.npz"
        assert _import([p for p in paths if p.stem.startswith(code)], out)[0] == 0
        nameless.append(out)
    rc, _, err = _run(["import", *map(str, nameless), "-o", str(tmp_path / "pool2.npz"), "-q"])
    assert rc == 0, err
    assert Corpus.load(tmp_path / "pool2.npz").speakers == ["nABCFIA", "nKLMFIB"]
    assert "speaker 'nABCFIA' given to the 3 utterance(s) of nABCFIA.npz that named none" in err


@pytest.mark.parametrize("rule, message", [
    ("re:^spk", "has 0 groups; expected exactly one group"),
    ("re:^(spk[0-9]+)", "does not match the speaker rule 're:^(spk[0-9]+)'"),
    ("re:([", "not a regular expression"),
    ("folder", "expected 'dir', 'prefix' or 're:PATTERN'"),
])
def test_a_rule_that_cannot_apply_is_refused_before_reading(lab_folder, tmp_path, rule, message):
    _, paths = lab_folder
    rc, _, err = _import(paths, tmp_path / "c.npz", "--speaker-from", rule)
    assert rc == 2 and message in err, err
    assert not (tmp_path / "c.npz").exists()
