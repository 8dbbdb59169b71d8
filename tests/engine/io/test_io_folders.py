"""A lab's folder as import inputs: its recordings in natural order, companions used, the rest named."""
from __future__ import annotations

from pathlib import Path

import pytest

from engine.io import ImportFormatError
from engine.io.folders import expand_folders


def _touch(folder: Path, *names):
    for n in names:
        p = folder / n
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(b"x")


def test_a_folder_gives_its_recordings_in_natural_order_and_says_what_it_left(tmp_path):
    d = tmp_path / "sweeps"
    _touch(d, "utt10.pos", "utt2.pos", "utt1.pos", "utt1.TextGrid", "utt2.wav", "tags.txt", "words.txt", ".DS_Store",
           "S2/utt1.pos")
    found = expand_folders([d])
    assert [Path(p).name for p in found.paths] == ["utt1.pos", "utt2.pos", "utt10.pos"]
    skipped = {Path(p).name: why for p, why in found.skipped}
    assert skipped["tags.txt"] == "not a .pos recording" and skipped[".DS_Store"] == "hidden"
    assert skipped["S2"].startswith("a subfolder (give --recursive")
    assert "utt1.TextGrid" not in skipped and "utt2.wav" not in skipped  # companions, used by the readers
    (note,) = found.notes
    assert "3 .pos recordings (pos) in natural order" in note and "tags.txt" in note


def test_recursive_reads_subfolders_and_keeps_ids_unique(tmp_path):
    d = tmp_path / "corpus"
    _touch(d, "S1/utt01.mat", "S1/utt02.mat", "S2/utt01.mat", "S10/utt01.mat", "README.md")
    found = expand_folders([d], recursive=True)
    rel = [Path(p).relative_to(d).as_posix() for p in found.paths]
    assert rel == ["S1/utt01.mat", "S1/utt02.mat", "S2/utt01.mat", "S10/utt01.mat"]
    assert found.ids[str(d / "S2/utt01.mat")] == "S2/utt01" and str(d / "S1/utt02.mat") not in found.ids
    assert all(r == str(d) for r in found.roots.values())


def test_binary_recordings_win_over_text_tables_and_the_format_decides(tmp_path):
    d = tmp_path / "mixed"
    _touch(d, "a.csv", "b.csv", "c.csv", "a.mat")
    assert [Path(p).name for p in expand_folders([d]).paths] == ["a.mat"]
    assert [Path(p).name for p in expand_folders([d], format="csv").paths] == ["a.csv", "b.csv", "c.csv"]
    assert [Path(p).name for p in expand_folders([d], format="matrix").paths] == ["a.mat"]


def test_mesh_and_video_folders_stay_whole_and_files_pass_through(tmp_path):
    _touch(tmp_path / "frames", "f0001.obj", "f0002.obj")
    _touch(tmp_path / "vids", "a.mp4", "a.TextGrid")
    _touch(tmp_path, "one.ema")
    found = expand_folders([tmp_path / "frames", tmp_path / "vids", tmp_path / "one.ema"])
    assert found.paths == [str(tmp_path / "frames"), str(tmp_path / "vids"), str(tmp_path / "one.ema")]


def test_a_folder_without_recordings_says_what_it_holds(tmp_path):
    d = tmp_path / "docs"
    _touch(d, "a.pdf", "b.docx", "sub/c.pos")
    with pytest.raises(ImportFormatError, match=r"docs: holds no recordings of a format .*2 files \(.docx, .pdf\) "
                                                 r"and 1 subfolders"):
        expand_folders([d])
    with pytest.raises(ImportFormatError, match=r"holds no wave recordings \(.tsv, .txt\)"):
        expand_folders([d], format="wave")


def test_the_ag501_sample_folder_gives_its_two_sweeps(shared_data):
    found = expand_folders([shared_data / "ag501-greek"])
    assert [Path(p).name for p in found.paths] == ["0021.pos", "0022.pos"]
    assert sorted(Path(p).name for p, _ in found.skipped) == ["0021-tags.txt", "0022-tags.txt", "SOURCE.txt",
                                                              "words.txt"]
