"""`lipspace import` of Haskins files keeps their AUDIO beside the corpus by default, as it does a video's."""
from __future__ import annotations

from app.cli import main
from engine.recordings.corpus import Corpus


def test_import_keeps_the_audio_entry_by_default_and_a_silent_file_makes_no_folder(make_haskins_file, tmp_path,
                                                                                   capsys):
    a = make_haskins_file(tmp_path / "F01_B01_S01_R01_N.mat", seconds=1.5)
    out = tmp_path / "ieee.npz"
    assert main(["import", str(a), "-o", str(out), "-q"]) == 0
    wav = tmp_path / "ieee_audio" / "F01_B01_S01_R01_N.wav"
    c = Corpus.load(out)
    assert wav.is_file() and c.utterances[0].audio == str(wav.resolve())
    assert [w.label for w in c.utterances[0].words] == ["sp", "BOB", "MEETS", "MUM", "sp"]
    silent = make_haskins_file(tmp_path / "M01.mat", seconds=1.0, audio=False)
    assert main(["import", str(silent), "-o", str(tmp_path / "m.npz"), "-q"]) == 0
    assert not (tmp_path / "m_audio").exists() and Corpus.load(tmp_path / "m.npz").utterances[0].audio is None
    capsys.readouterr()
