"""What the commands write: never an existing user file without --force (the refusal names it), all of a
command's outputs or none after a failure, a stop or a full disk, the message matching what is on disk, and
the user's file named (never a temporary one). A full disk is simulated by making the writer raise ENOSPC;
benchmarks/campaign_bad_input.py runs the same cases on a real tiny tmpfs."""
from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from app.cli import main

PHONES = "p 0.1 aa 0.1"


@pytest.fixture(scope="module")
def mfile(tiny_manifold_file):
    return tiny_manifold_file


def _mine(p, text=b"a user's own file\n"):
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_bytes(text)
    return p


def _left(d):
    return sorted(str(p.relative_to(d)) for p in d.rglob("*") if ".part" in p.name)


def _mat(path):
    import scipy.io

    dt = [("NAME", "O"), ("SRATE", "O"), ("SIGNAL", "O"), ("SENTENCE", "O"), ("PHONES", "O")]
    s = np.zeros((1, 3), dtype=dt)
    rng = np.random.default_rng(0)
    s[0, 0] = ("AUDIO", 44100.0, (rng.normal(size=(4410, 1)) * 0.1).astype(np.float32), "", np.zeros((0, 0)))
    s[0, 1] = ("UL", 100.0, rng.normal(size=(50, 6)).astype(np.float32), "", np.zeros((0, 0)))
    s[0, 2] = ("LL", 100.0, rng.normal(size=(50, 6)).astype(np.float32), "", np.zeros((0, 0)))
    scipy.io.savemat(path, {path.stem: s})
    return path


# ------------------------------------------------------------------ item 2: no overwrite without --force
def test_audio_dir_never_overwrites_a_users_wav(tmp_path, capsys):
    src = [_mat(tmp_path / "a.mat"), _mat(tmp_path / "b.mat")]
    wav = _mine(tmp_path / "aud" / "b.wav")
    out = tmp_path / "c.npz"
    argv = ["import", *map(str, src), "-o", str(out), "--audio-dir", str(tmp_path / "aud"), "-q", "--points", "UL,LL"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{wav} (--audio-dir) already exists; nothing was written. Pass --force" in err, err
    assert wav.read_bytes() == b"a user's own file\n" and not out.exists() and not (tmp_path / "aud" / "a.wav").exists()
    assert main(argv + ["--force"]) == 0
    assert wav.read_bytes()[:4] == b"RIFF" and (tmp_path / "aud" / "a.wav").is_file() and _left(tmp_path) == []


@pytest.mark.parametrize("command", ["synthesize -o", "synthesize --mesh-dir", "figures", "clusters", "build",
                                     "evaluate --markdown", "glb wav"])
def test_every_output_refuses_an_existing_file(mfile, tmp_path, capsys, command):
    m = str(mfile)
    mine = {"synthesize -o": tmp_path / "t.csv", "synthesize --mesh-dir": tmp_path / "mesh" / "frame_00007.obj",
            "figures": tmp_path / "figs" / "scree.png", "clusters": tmp_path / "t.csv", "build": tmp_path / "m.npz",
            "evaluate --markdown": tmp_path / "r.md", "glb wav": tmp_path / "a.wav"}[command]
    argv = {"synthesize -o": ["synthesize", "--manifold", m, "--phones", PHONES, "-o", str(mine)],
            "synthesize --mesh-dir": ["synthesize", "--manifold", m, "--phones", PHONES, "--mesh-dir",
                                      str(mine.parent)],
            "figures": ["figures", m, "-o", str(mine.parent), "--only", "scree", "-q"],
            "clusters": ["clusters", m, "--csv", str(mine), "-q"],
            "build": ["build", str(Path(m).with_name("corpus.npz")), "-o", str(mine), "-q"],
            "evaluate --markdown": ["evaluate", str(Path(m).with_name("corpus.npz")), "--markdown", str(mine), "-q"],
            "glb wav": ["synthesize", "--manifold", m, "--phones", PHONES, "-o", str(tmp_path / "a.glb"), "--audio",
                        str(_mine(tmp_path / "in" / "sound.wav"))]}[command]
    _mine(mine)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert str(mine) in err and "already exist" in err and "--force" in err and err.count("\n") == 1, err
    assert mine.read_bytes() == b"a user's own file\n" and _left(tmp_path) == []
    assert not (tmp_path / "a.glb").exists()


def test_force_replaces_a_frame_sequence_whole(mfile, tmp_path, capsys):
    """--mesh-dir --force: the folder holds exactly the new frames (an old longer sequence's tail removed);
    other files in it stay."""
    mesh = tmp_path / "mesh"
    for k in range(40):
        _mine(mesh / f"frame_{k:05d}.obj")
    _mine(mesh / "notes.txt")
    assert main(["synthesize", "--manifold", str(mfile), "--phones", PHONES, "--mesh-dir", str(mesh), "--force"]) == 0
    names = sorted(p.name for p in mesh.iterdir())
    assert names[-1] == "notes.txt" and len(names) == 13 and names[-2] == "frame_00011.obj"
    assert (mesh / "frame_00000.obj").read_bytes() != b"a user's own file\n"


# ------------------------------------------------------------------ item 4: all outputs or none
def test_a_signal_while_outputs_move_in_lets_them_all_land(mfile, tmp_path, capsys, monkeypatch):
    """SIGTERM arriving while the finished outputs are moved into place: all of them land, exit 0, and the
    message says the signal came too late, instead of 'nothing was written' over files that exist."""
    import engine.files.staging as staging

    real = staging.move_noreplace
    sent = []

    def replace(src, dst):
        if not sent and Path(dst).parent == tmp_path / "mesh":  # a finished frame moving into the user's folder
            sent.append(1)
            os.kill(os.getpid(), signal.SIGTERM)
        return real(src, dst)

    monkeypatch.setattr(staging, "move_noreplace", replace)
    out = tmp_path / "t.csv"
    assert main(["synthesize", "--manifold", str(mfile), "--phones", PHONES, "--mesh-dir", str(tmp_path / "mesh"),
                 "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "SIGTERM arrived when the command could no longer stop" in err and "nothing was written" not in err
    assert out.is_file() and len(list((tmp_path / "mesh").iterdir())) == 12 and _left(tmp_path) == []


def test_a_full_disk_while_audio_is_written_stops_the_import(tmp_path, capsys, monkeypatch):
    """The campaign's 96-file import skipped every file on ENOSPC and exited 0 with 2 utterances."""
    import scipy.io.wavfile

    src = [_mat(tmp_path / f"s{k}.mat") for k in range(4)]
    real, calls = scipy.io.wavfile.write, []

    def full(path, *a, **k):
        calls.append(path)
        if len(calls) == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(path, *a, **k)

    monkeypatch.setattr(scipy.io.wavfile, "write", full)
    out = tmp_path / "c.npz"
    rc = main(["import", *map(str, src), "-o", str(out), "--audio-dir", str(tmp_path / "aud"), "-q", "--jobs", "1",
               "--points", "UL,LL", "--skip-bad"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1, err
    assert f"{tmp_path / 'aud' / 's2.wav'}: No space left on device (the disk is full" in err, err
    assert not out.exists() and not (tmp_path / "aud").exists() and _left(tmp_path) == []


def test_a_full_disk_while_figures_are_saved_leaves_none(mfile, tmp_path, capsys, monkeypatch):
    """The campaign's figures on a full disk left two PNGs and named no file."""
    from matplotlib.figure import Figure

    real, calls = Figure.savefig, []

    def full(self, fname, *a, **k):
        calls.append(fname)
        if len(calls) == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, fname, *a, **k)

    monkeypatch.setattr(Figure, "savefig", full)
    figs = tmp_path / "figs"
    assert main(["figures", str(mfile), "-o", str(figs), "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{figs}{os.sep}" in err and ".part" not in err and "No space left on device" in err, err
    assert not figs.exists() and _left(tmp_path) == []


def test_a_read_only_folder_names_the_users_file(mfile, tmp_path, capsys, monkeypatch):
    import tempfile

    def ro(*a, **k):
        raise OSError(errno.EROFS, "Read-only file system", str(Path(k.get("dir", ".")) / ".t.part-x1y2.csv"))

    monkeypatch.setattr(tempfile, "mkstemp", ro)
    out = tmp_path / "t.csv"
    assert main(["synthesize", "--manifold", str(mfile), "--phones", PHONES, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{out}: Read-only file system (a read-only file system: write elsewhere)" in err and ".part" not in err


# ------------------------------------------------------------------ item 6: the option typed, the real cause
@pytest.mark.parametrize("argv, says", [
    (["--smoothing", "inf"], "--smoothing inf: must be a finite number from 0 to 3600 frames"),
    (["--smoothing", "1e9"], "--smoothing 1e9: must be from 0"),
    (["--smoothing", "nan"], "--smoothing nan"),
    (["--candidates", "0"], "--candidates 0: must be from 1 to 1000"),
    (["--gltf-scale", "inf"], "--gltf-scale inf"),
])
def test_numeric_options_are_refused_by_name(mfile, capsys, argv, says):
    assert main(["synthesize", "--manifold", str(mfile), "--phones", PHONES, *argv]) == 2
    err = capsys.readouterr().err
    assert says in err and "--inverse-dims" not in err and err.count("\n") == 1, err


def test_key_frames_beyond_any_index_and_render_options(mfile, tmp_path, capsys):
    from engine.manifold.model import Manifold

    uid = Manifold.load(mfile).corpus_.utterances[0].id
    assert main(["synthesize", "--manifold", str(mfile), "--utterance", uid, "--key-frames", "0," + "1" * 31]) == 2
    err = capsys.readouterr().err
    assert f"utterance {uid!r}: key frames" in err and "are not frame indices" in err and "key_frames" not in err
    for opt, value in (("--smoothing", "inf"), ("--crf", "99")):
        assert main(["render", "--manifold", str(mfile), "--phones", PHONES, opt, value, "-o",
                     str(tmp_path / "v.mp4")]) == 2
        assert f"{opt} {value}" in capsys.readouterr().err
    for opt, value in (("--rate", "0"), ("--rate", "inf"), ("--interocular-mm", "nan")):
        assert main(["import", str(mfile), "-o", str(tmp_path / "c.npz"), opt, value]) == 2
        assert f"{opt} {value}" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_an_ascii_terminal_gets_escapes_not_a_traceback(mfile, tmp_path):
    """The campaign's PYTHONIOENCODING=ascii run failed after the output file was written."""
    from engine.files.persist import read_npz

    d = read_npz(Path(mfile).with_name("corpus.npz"))
    d["corpus_name"] = np.array("café – ü")
    with open(tmp_path / "c.npz", "wb") as fh:
        np.savez(fh, **d)
    env = dict(os.environ, PYTHONIOENCODING="ascii")
    r = subprocess.run([sys.executable, "-m", "app.cli", "info", str(tmp_path / "c.npz")], capture_output=True,
                       text=True, env=env)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert "caf\\xe9 \\u2013 \\xfc" in r.stdout


@pytest.mark.skipif(__import__("shutil").which("espeak-ng") is None, reason="espeak-ng is not installed")
def test_render_of_typed_text_carries_the_text_spoken(mfile, tmp_path, capsys):
    """`lipspace render --text`: the MP4 has an audio stream, the text said on the synthesis's phone times."""
    import av

    out = tmp_path / "bob.mp4"
    assert main(["render", "--manifold", str(mfile), "--text", "bob meets mum", "--method", "linear", "-o", str(out),
                 "--size", "64x48", "-q"]) == 0
    assert "with audio" in capsys.readouterr().out
    with av.open(str(out)) as f:
        streams = [s.type for s in f.streams]
        assert streams.count("audio") == 1 and streams.count("video") == 1
