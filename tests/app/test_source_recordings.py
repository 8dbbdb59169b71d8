"""A recording opened by itself (File > Open, ``lipspace explore FILE``) is fitted as ``lipspace
import`` then ``build`` would fit it: resampled to the 60-Hz analysis rate and registered with
import's defaults (before, the window fitted a 500-Hz MOCHA file at 500 Hz: 32 states and a split
state graph where import + build gave 4 connected states)."""
from __future__ import annotations

import numpy as np

from app.cli import main


def _csv_recording(path, rate=200.0, seconds=4.0):
    """Two lips and two corners moving at syllable rate, as a CSV with named columns and a time column."""
    t = np.arange(int(rate * seconds)) / rate
    rng = np.random.default_rng(3)
    opening = 5 + 4 * np.sin(2 * np.pi * 4.1 * t) + 0.3 * rng.standard_normal(t.size)
    spread = 25 + 2 * np.sin(2 * np.pi * 1.3 * t + 0.4)
    cols = {"time": t, "UL_x": 0 * t, "UL_y": opening / 2, "LL_x": 0 * t, "LL_y": -opening / 2,
            "LC_x": -spread, "LC_y": 0.2 * opening, "RC_x": spread, "RC_y": 0.2 * opening}
    lines = [",".join(cols)] + [",".join(f"{cols[c][i]:.6f}" for c in cols) for i in range(t.size)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_recording_opened_directly_is_fitted_at_the_analysis_rate_as_import_makes_it(tmp_path, capsys):
    from app.files.source_loading import load_source, source_kind

    rec = _csv_recording(tmp_path / "take1.csv")
    assert source_kind(rec) == "foreign"
    m, src = load_source(rec, prepare_views=False)
    c = m.corpus_
    assert src["path"] == str(rec.resolve()) and src["kind"] == "foreign"
    assert c.rate == 60.0
    assert c.n_frames == 240  # 4 s at 60 Hz, not 800 frames at 200 Hz
    assert any(h.startswith("resampled 200 -> 60 Hz") for h in c.history), c.history
    # the same frames as 'lipspace import' with its defaults
    assert main(["import", str(rec), "-o", str(tmp_path / "take1.npz")]) == 0
    capsys.readouterr()
    from engine.recordings.corpus import Corpus

    imported = Corpus.load(tmp_path / "take1.npz")
    np.testing.assert_allclose(c.frames, imported.frames, rtol=1e-6, atol=1e-9)
    assert c.registration == imported.registration


def test_build_of_a_recording_fits_what_import_makes(tmp_path, capsys):
    """`lipspace build rec.csv` (and figures, clusters: app.cli._common.load_corpus_arg) read a foreign
    file as the window does: at 60 Hz with import's defaults, so no rate warning (before: fitted at
    200 Hz with a warning to run import first)."""
    from engine.manifold.model import Manifold
    from engine.recordings.corpus import Corpus

    rec = _csv_recording(tmp_path / "take2.csv")
    assert main(["build", str(rec), "-o", str(tmp_path / "m.npz"), "-q"]) == 0
    err = capsys.readouterr().err
    assert "analysis rate" not in err, err
    assert main(["import", str(rec), "-o", str(tmp_path / "take2.npz")]) == 0
    c = Manifold.load(tmp_path / "m.npz").corpus_
    assert c.rate == 60.0 and c.n_frames == 240
    np.testing.assert_allclose(c.frames, Corpus.load(tmp_path / "take2.npz").frames, rtol=1e-6, atol=1e-9)
