"""``lipspace import`` on a lab's folder: the folder read in order with what was left said, metadata fields from
file names and from the lab's table, sensor quality reported and acted on, and bad metadata refused or warned
about, naming the file and the field, with nothing lost."""
from __future__ import annotations

import csv

import numpy as np

from engine.recordings.corpus import Corpus
from engine.recordings.metadata import field_levels, field_names, field_values

PATTERN = r"re:^(?P<speaker>[A-Z]+?)(?P<sex>[FM])(?P<emotion>[A-Z]{2})(?P<text>[0-9]+)$"


def _import(cli, folder, out, *extra):
    return cli(["import", str(folder), "--layout", str(folder / "lab.layout"), "-q", "--jobs", "1", "-o", str(out),
                *extra])


def test_a_folder_with_a_file_name_pattern(ag501_lab, tmp_path, cli):
    folder, sweeps, paths = ag501_lab
    rc, out, err = _import(cli, folder, tmp_path / "c.npz", "--fields-from", PATTERN)
    assert rc == 0, err
    assert f"folder {folder}: 18 .pos recordings (matrix) in natural order; left out 3: lab.layout, metadata.csv, " \
           "notes.txt" in err
    c = Corpus.load(tmp_path / "c.npz")
    assert [u.id for u in c.utterances] == sorted((p.stem for p in paths), key=lambda s: s.lower())
    assert field_names(c) == ["speaker", "sex", "emotion", "text"]
    assert sorted(c.speakers) == ["ABCD", "EF", "XYZ"]
    assert {lv: n for lv, n, _ in field_levels(c, "emotion")} == {"NE": 6, "AN": 6, "SA": 6}
    assert field_values(c, "sex").tolist() == [s.sex for s in sorted(sweeps, key=lambda s: s.name.lower())]
    assert "warning" not in err  # the pattern names the speakers: no speaker suggestion


def test_the_lab_table_with_missing_and_extra_rows_is_warned_about_and_nothing_is_lost(ag501_lab, tmp_path, cli):
    folder, sweeps, paths = ag501_lab
    rc, out, err = _import(cli, folder, tmp_path / "c.npz", "--metadata", str(folder / "metadata.csv"))
    assert rc == 0, err
    assert f"warning: {folder / 'metadata.csv'}: no row for 1 of 18 inputs (EFFSA02.pos); their fields speaker, sex, " \
           "emotion, text, session are missing (NA)" in err
    assert "1 row names no input (QRSMNE01.pos; line 19); it was not used" in err
    c = Corpus.load(tmp_path / "c.npz")
    assert len(c.utterances) == 18  # the recording without a row is kept
    assert field_values(c, "session").tolist().count("") == 1 and c.utterance("EFFSA02").speaker == ""


def test_pattern_and_table_together_and_their_conflicts(ag501_lab, tmp_path, cli):
    folder, *_ = ag501_lab
    rc, _, err = _import(cli, folder, tmp_path / "c.npz", "--fields-from", PATTERN, "--metadata",
                         str(folder / "metadata.csv"))
    assert rc == 0, err
    c = Corpus.load(tmp_path / "c.npz")
    assert c.utterance("EFFSA02").speaker == "EF"  # the pattern names what the table misses
    bad = tmp_path / "bad.csv"
    bad.write_text("file,emotion\nXYZFNE01.pos,HA\n")
    rc, _, err = _import(cli, folder, tmp_path / "d.npz", "--fields-from", PATTERN, "--metadata", str(bad))
    assert rc == 2 and "XYZFNE01.pos: field 'emotion' is 'NE' by --fields-from but 'HA' in" in err
    rc, _, err = _import(cli, folder, tmp_path / "d.npz", "--fields-from", PATTERN, "--speaker", "X")
    assert rc == 2 and "--speaker and a 'speaker' field (--fields-from) both name the speakers" in err
    assert not (tmp_path / "d.npz").exists()


def test_a_pattern_that_matches_nothing_names_the_files(ag501_lab, tmp_path, cli):
    folder, *_ = ag501_lab
    rc, _, err = _import(cli, folder, tmp_path / "c.npz", "--fields-from", r"re:^(?P<speaker>S[0-9]+)_")
    assert rc == 2 and "matches none of the 18 file names" in err and "ABCDMAN01" in err
    assert not (tmp_path / "c.npz").exists()


def test_without_fields_the_names_structure_is_suggested_and_right(ag501_lab, tmp_path, cli):
    folder, *_ = ag501_lab
    rc, _, err = _import(cli, folder, tmp_path / "c.npz")
    assert rc == 0
    assert "all 18 inputs are one unnamed speaker" in err and "3 speakers x 3 condition levels x 2 item levels" in err
    assert "speaker 3 levels (ABCDM 6, EFF 6, XYZF 6 files)" in err


def test_quality_is_reported_per_speaker_and_masked_or_dropped(ag501_lab, tmp_path, cli):
    folder, *_ = ag501_lab
    report = tmp_path / "quality.csv"
    rc, _, err = _import(cli, folder, tmp_path / "k.npz", "--fields-from", PATTERN, "--quality-report", str(report))
    assert rc == 0, err
    line = next(x for x in err.splitlines() if "quality: UL:" in x)
    import re

    med = {k: float(v) for k, v in re.findall(r"speaker (\w+) median ([0-9.]+)", line)}
    assert med["XYZ"] > 7 and med["ABCD"] < 4 and med["EF"] < 4  # the bad coil, named with its speaker
    assert "quality: keep: every sample kept as recorded" in err
    rows = list(csv.DictReader(report.read_text().splitlines()))
    assert len(rows) == 18 * 7 and set(rows[0]) >= {"utterance", "sensor", "share_above", "longest_run_s", "action"}
    xyz_ul = [float(r["share_above"]) for r in rows if r["sensor"] == "UL" and r["utterance"].startswith("XYZ")]
    assert min(xyz_ul) > 0.5
    rc, info, _ = cli(["info", str(tmp_path / "k.npz")])
    assert rc == 0 and "\nquality     rms above" in info and "keep: every sample kept as recorded" in info
    assert "\nfields      speaker 3 levels" in info and "            emotion 3 levels: AN 6, NE 6, SA 6" in info
    rc, _, err = _import(cli, folder, tmp_path / "d.npz", "--fields-from", PATTERN, "--quality", "drop")
    assert rc == 0, err
    c = Corpus.load(tmp_path / "d.npz")
    assert "XYZ" not in c.speakers and "utterance(s) with longer runs dropped: XYZF" in err
    rc, _, err = _import(cli, folder, tmp_path / "m.npz", "--fields-from", PATTERN, "--quality", "mask",
                         "--quality-threshold", "12", "--quality-max-gap", "40")
    assert rc == 0, err
    assert "quality: mask at threshold 12:" in err and "runs of at most 10 frames (40 ms)" in err


def test_quality_asked_of_files_without_it_is_refused(lab_folder, tmp_path, cli):
    folder, paths = lab_folder  # MAT files with the 6-value layout: ema7x6 has rms at value 5
    rc, _, err = cli(["import", *map(str, paths), "--layout", "ema7x6", "-q", "--jobs", "1", "-o",
                      str(tmp_path / "c.npz"), "--quality", "mask"])
    assert rc == 0, err  # ema7x6 has an rms value
    rc, _, err = cli(["import", str(folder), "--format", "mview", "-q", "--jobs", "1", "-o", str(tmp_path / "d.npz"),
                      "--quality", "drop"])
    assert rc == 2


def test_recursive_folders_of_speakers(ag501_lab, tmp_path, cli):
    import shutil

    folder, sweeps, paths = ag501_lab
    root = tmp_path / "corpus"
    for spk, d in (("ABCD", root / "S1"), ("XYZ", root / "S2")):
        d.mkdir(parents=True)
        for k, p in enumerate([p for p in paths if p.stem.startswith(spk)][:2]):
            shutil.copy(p, d / f"take{k + 1:02d}.pos")
    rc, _, err = cli(["import", str(root), "--layout", str(folder / "lab.layout"), "-q", "--jobs", "1", "-o",
                      str(tmp_path / "c.npz")])
    assert rc == 2 and "holds no matrix recordings" in err and "0 files (none) and 2 subfolders" in err
    rc, _, err = cli(["import", str(root), "-r", "--layout", str(folder / "lab.layout"), "-q", "--jobs", "1",
                      "--speaker-from", "dir", "-o", str(tmp_path / "c.npz")])
    assert rc == 0, err
    c = Corpus.load(tmp_path / "c.npz")
    assert [u.id for u in c.utterances] == ["S1/take01", "S1/take02", "S2/take01", "S2/take02"]
    assert c.speakers == ["S1", "S2"]


def test_the_real_ag501_folder_imports_with_its_tag_files_left_out(shared_data, tmp_path, cli):
    rc, _, err = cli(["import", str(shared_data / "ag501-greek"), "-q", "--jobs", "1", "--points", "ch6,ch7,ch8",
                      "--roles", "upper_lip=ch6;lower_lip=ch7;jaw=ch8", "-o", str(tmp_path / "g.npz")])
    assert rc == 0, err
    assert "2 .pos recordings (pos) in natural order; left out 4: 0021-tags.txt, 0022-tags.txt, SOURCE.txt, " \
           "words.txt" in err
    assert "quality: no rms above 9.27 in ch6 (median 2.89), ch7 (median 3.36), ch8 (median 3.07)" in err
    c = Corpus.load(tmp_path / "g.npz")
    assert [u.id for u in c.utterances] == ["0021", "0022"] and np.isfinite(np.asarray(c.frames)).all()


def test_recursive_folders_of_mesh_frames_are_one_utterance_each(tmp_path, cli):
    from engine.io.writers.meshfile import write_obj

    root = tmp_path / "meshes"
    for k, name in enumerate(("sentence02", "sentence10", "sentence01")):
        for i in range(12):
            V = np.array([[0, 0, 0], [10, 0, 0], [0, 5 + np.sin(i / 2 + k), 0]], float)
            write_obj(root / name / f"frame{i:03d}.obj", V, np.array([[0, 1, 2]]))
    rc, _, err = cli(["import", str(root), "-r", "--rate", "60", "-q", "--jobs", "1", "-o", str(tmp_path / "m.npz")])
    assert rc == 0, err
    assert "3 subfolders read as one recording each (sentence01, sentence02, sentence10)" in err
    c = Corpus.load(tmp_path / "m.npz")
    assert len(c.utterances) == 3 and [u.n_frames for u in c.utterances] == [12, 12, 12]


def test_a_folder_of_ndi_wave_exports_with_state_and_error_columns(tmp_path, cli):
    from engine.talker.lab_files import lab_sweeps, wave_tsv

    d = tmp_path / "wave"
    d.mkdir()
    for _k, s in enumerate(lab_sweeps(speakers=(("S01", "F"), ("S02", "M")), emotions=("NE",), texts=2,
                                     duration_s=(0.8, 0.9), seed=4)):
        X = s.positions[::2, 5:9]  # UL LL LC RC at 125 Hz
        err = np.full(X.shape[:2], 0.3)
        state = np.full(X.shape[:2], "OK", dtype=object)
        if s.speaker == "S02":
            err[20:24, 0] = 1.5  # a short burst on the upper lip
            state[30, 1] = "Missing"
        (d / f"{s.name}.tsv").write_text(wave_tsv(X, rate=125.0, state=state, error=err))
    (d / "layout.txt").write_text("base: wave\nsensor UL upper_lip\nsensor LL lower_lip\nsensor LC left_corner\n"
                                  "sensor RC right_corner\n")
    rc, _, err = cli(["import", str(d), "--format", "wave", "--layout", str(d / "layout.txt"), "-q", "--jobs", "1",
                      "--fields-from", r"re:^(?P<speaker>S[0-9]+)(?P<sex>[FM])", "--quality", "mask",
                      "--quality-threshold", "1", "-o", str(tmp_path / "w.npz")])
    assert rc == 0, err
    assert "4 .tsv recordings (wave)" in err and "left out 1: layout.txt" in err
    assert "quality: UL: speaker S01 median 0.3, 0.0% of samples above" in err
    assert "mask at threshold 1: 8 samples in runs of at most 6 frames (50 ms) above it interpolated" in err
    assert "status not OK" in err
    c = Corpus.load(tmp_path / "w.npz")
    assert c.speakers == ["S01", "S02"] and field_values(c, "sex").tolist() == ["F", "F", "M", "M"]
