"""``lipspace import``: foreign formats -> native corpus file, with a one-line summary."""
from pathlib import Path

import numpy as np
import pytest

from app.cli import SUBCOMMANDS, CliError, importer
from engine.io import write_est_track, write_mesh_sequence
from engine.recordings.corpus import Corpus


def _repo_root():
    p = Path(__file__).resolve()
    while not (p / "pyproject.toml").exists():
        p = p.parent
    return p


DATA = _repo_root().parent / "shared" / "data"
needs_data = pytest.mark.skipif(not (DATA / "mocha-fsew0").is_dir() or not (DATA / "haskins-ieee").is_dir(),
                                reason=f"real sample data not found at {DATA} (../shared/data beside the project)")


def run(argv):
    """What ``lipspace import ARGV`` does (app.cli.main's handling of CliError and OSError included),
    its error on stdout."""
    from app.cli import _os_error_text, build_parser

    assert SUBCOMMANDS["import"][0] == "app.cli.importer"
    args = build_parser("import").parse_args(["import", *argv])
    try:
        return importer.run(args)
    except CliError as exc:
        print(f"lipspace import: error: {exc}")
        return 2
    except OSError as exc:
        print(f"lipspace import: error: {_os_error_text(exc)}")
        return 2


@needs_data
def test_import_mocha_with_resampling(tmp_path, capsys):
    out = tmp_path / "m.npz"
    assert run([str(DATA / "mocha-fsew0" / "fsew0_001.ema"), "-o", str(out), "--resample", "60"]) == 0
    line = capsys.readouterr().out.strip()
    c = Corpus.load(out)
    assert c.rate == 60 and c.dims == 2 and c.n_points == 3 and c.n_frames == 116
    assert line == (f"wrote {out}: 116 frames, 3 points (2-D), 60 Hz, 1 utterance, 18 phones (13 labels), "
                    f"{116 / 60:.2f} s")


@needs_data
def test_import_both_haskins_files_with_audio(tmp_path, capsys):
    files = sorted(str(p) for p in (DATA / "haskins-ieee").glob("*.mat"))
    out = tmp_path / "h.npz"
    from engine.recordings.speakers import SpeakerWarning

    with pytest.warns(SpeakerWarning, match="all 2 inputs are one unnamed speaker"):  # F01_..., M01_...
        assert run([*files, "-o", str(out), "--audio-dir", str(tmp_path / "wav")]) == 0
    c = Corpus.load(out)
    # the default analysis rate and c.point_names[:2] == ["UL", "LL"]
    assert len(c.utterances) == 2 and c.rate == 60 and c.dims == 3
    for u in c.utterances:
        assert Path(u.audio).is_file() and Path(u.audio).stem == u.id
    assert "2 utterances" in capsys.readouterr().out


@needs_data
def test_import_errors_are_clean(tmp_path, capsys):
    ema = str(DATA / "mocha-fsew0" / "fsew0_001.ema")
    assert run([ema, "-o", str(tmp_path / "x.npz"), "--rate", "60"]) == 2
    assert "500 Hz but a rate of 60 Hz was given (--rate)" in capsys.readouterr().out
    assert run([ema, "-o", str(tmp_path / "x.npz"), "--points", "UL,NOSE"]) == 2
    assert "no sensor(s) ['NOSE']" in capsys.readouterr().out
    assert run([str(DATA / "mocha-fsew0" / "fsew0_001.lab"), "-o", str(tmp_path / "x.npz")]) == 2
    assert "is a phone alignment" in capsys.readouterr().out
    assert run([ema, "-o", str(tmp_path / "x.txt")]) == 2
    assert run([str(tmp_path / "none.ema"), "-o", str(tmp_path / "x.npz")]) == 2
    assert "no such file" in capsys.readouterr().out
    assert not list(tmp_path.glob("x.*"))


def test_import_mesh_directory_with_alignment_and_rate(tmp_path, capsys):
    P = np.random.default_rng(0).normal(size=(20, 5, 3))
    write_mesh_sequence(tmp_path / "frames", P, faces=[[0, 1, 2], [2, 3, 4]], format="ply", binary=True)
    tg = tmp_path / "a.TextGrid"
    tg.write_text('File type = "ooTextFile"\nObject class = "TextGrid"\n\n0\n0.4\n<exists>\n1\n"IntervalTier"\n'
                  '"phones"\n0\n0.4\n2\n0\n0.2\n"m"\n0.2\n0.4\n"a"\n')
    out = tmp_path / "c.npz"
    assert run([str(tmp_path / "frames"), "--rate", "50", "--alignment", str(tg), "-o", str(out),
                "--resample", "native"]) == 0
    c = Corpus.load(out)
    assert c.n_frames == 20 and c.rate == 50 and c.faces.shape == (2, 3)
    assert [p.label for p in c.utterances[0].phones] == ["m", "a"]
    assert run([str(tmp_path / "frames"), "-o", str(out), "--force"]) == 2
    assert "give the frame rate (lipspace import --rate HZ)" in capsys.readouterr().out


def test_import_est_with_points_and_no_fill(tmp_path, capsys):
    t = np.arange(40) / 250.0
    v = np.random.default_rng(1).normal(size=(40, 4)) * 100
    valid = np.ones(40, bool)
    valid[5] = False
    src = write_est_track(tmp_path / "s.ema", t, v, ["ul_x", "ul_y", "ll_x", "ll_y"], valid=valid)
    out = tmp_path / "s.npz"
    assert run([str(src), "--points", "ll", "-o", str(out), "--name", "demo", "--resample", "native"]) == 0
    c = Corpus.load(out)
    assert c.point_names == ["LL"] and c.name == "demo" and c.rate == 250
    assert run([str(src), "--no-fill", "--points", "UL,LL", "-o", str(out), "--force"]) == 2
    assert "frame 5" in capsys.readouterr().out
