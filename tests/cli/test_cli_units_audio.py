"""Messages carry their unit (registration shifts in mm, what cross-speaker centring and speaker normalisation
moved), and a corpus stores audio paths relative to its own file, so a moved folder keeps its sound."""
import contextlib
import io
import os
import shutil

import numpy as np

from app.cli import main
from engine.recordings.corpus import Corpus


def _run(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, out.getvalue(), err.getvalue()


def _with_sound(paths):
    from engine.files.atomic import write_wav_atomic

    for p in paths:
        write_wav_atomic(p.with_suffix(".wav"), np.zeros(1600, np.float32), 16000)


def test_registration_and_normalisation_say_what_they_moved_with_units(lab_folder, tmp_path):
    _, paths = lab_folder
    out = tmp_path / "c.npz"
    rc, _, err = _run(["import", *map(str, paths), "--layout", "ema7x6", "-q", "--jobs", "1", "--speaker-from",
                       "re:^([A-Z]{3})", "-o", str(out)])
    assert rc == 0, err
    line = next(ln for ln in err.splitlines() if "utterance centring" in ln)
    assert " mm, max " in line and line.endswith(" mm (9 utterances)"), line
    rc, _, err = _run(["import", *map(str, paths), "--layout", "ema7x6", "-q", "--jobs", "1", "--speaker-from",
                       "re:^([A-Z]{3})", "--register", "speaker", "-o", str(tmp_path / "s.npz")])
    line = next(ln for ln in err.splitlines() if "speaker centring" in ln)
    assert "frames moved ABC by " in line and " mm, KLM by " in line and " mm, XYM by " in line, line
    m = tmp_path / "m.npz"
    rc, _, err = _run(["build", str(out), "-o", str(m), "-q", "--states", "20"])
    assert rc == 0, err
    rc, info, _ = _run(["info", str(m)])
    line = next(ln for ln in info.splitlines() if "speaker normalisation mean over 3 speakers" in ln)
    assert "each speaker's mean frame moved to the pooled mean frame (RMS over the points): ABC by " in line
    assert line.count(" mm") == 3, line


def test_a_moved_folder_keeps_its_sound(lab_folder, tmp_path):
    _, paths = lab_folder
    lab = tmp_path / "lab"
    shutil.copytree(paths[0].parent, lab)
    files = sorted(lab.glob("*.mat"))
    _with_sound(files)
    corpus = lab / "corpus.npz"
    rc, _, err = _run(["import", *map(str, files), "--layout", "ema7x6", "-q", "--jobs", "1", "--speaker-from",
                       "re:^([A-Z]{3})", "-o", str(corpus)])
    assert rc == 0, err
    import zipfile

    with zipfile.ZipFile(corpus) as z, z.open("corpus_utt_audio.npy") as fh:
        stored = np.lib.format.read_array(fh)
    assert [str(a) for a in stored] == [f.with_suffix(".wav").name for f in files]  # relative to the corpus file
    rc, _, err = _run(["build", str(corpus), "-o", str(lab / "m.npz"), "-q", "--states", "20"])
    assert rc == 0, err
    # a corpus file moved on its own still finds the sound where it is
    alone = tmp_path / "alone.npz"
    shutil.copy(corpus, alone)
    assert all(os.path.isfile(u.audio) and os.path.dirname(u.audio) == str(lab) for u in Corpus.load(alone).utterances)
    moved = tmp_path / "elsewhere" / "lab2"
    shutil.move(str(lab), str(moved))
    for name in ("corpus.npz", "m.npz"):
        from engine.manifold.model import Manifold

        c = Corpus.load(moved / name) if name == "corpus.npz" else Manifold.load(moved / name).corpus_
        assert [os.path.dirname(u.audio) for u in c.utterances] == [str(moved)] * len(files)
        assert all(os.path.isfile(u.audio) for u in c.utterances)


def test_old_files_with_absolute_audio_paths_still_load(tmp_path):
    wav = tmp_path / "sound" / "u1.wav"
    wav.parent.mkdir()
    from engine.files.atomic import write_wav_atomic
    from engine.recordings.corpus import Utterance

    write_wav_atomic(wav, np.zeros(800, np.float32), 16000)
    c = Corpus(frames=np.zeros((10, 6), np.float32), rate=60.0, utterances=[Utterance("u1", 0, 10, audio=str(wav))])
    d = c.to_arrays()  # as files were written before: absolute paths, no base, no unit
    d.pop("corpus_units")
    np.savez(tmp_path / "old.npz", **d)
    old = Corpus.load(tmp_path / "old.npz")
    assert old.utterances[0].audio == str(wav) and old.units == "" and old.unit_label == "data units"
