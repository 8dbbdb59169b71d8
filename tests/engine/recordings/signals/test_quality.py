"""Sensor quality from AG501 / AG500 .pos rms and NDI Wave error columns: read, reported per sensor and utterance,
and acted on (keep, mask short runs, drop utterances) with every action said."""
from __future__ import annotations

import numpy as np
import pytest

from engine.io import read_corpus
from engine.io.readers.articulograph import read_pos, read_wave
from engine.io.repairs import collecting_repairs
from engine.recordings.signals.quality import (
    QualityPolicy,
    action_line,
    apply_quality,
    quality_rows,
    resolve_threshold,
    runs_of,
    sensor_quality,
    summary_lines,
)
from engine.talker.lab_files import SOCKETS, lab_sweeps, layout_text, pos_bytes, wave_tsv, write_pos


@pytest.fixture(scope="module")
def sweep():
    return lab_sweeps(speakers=(("XYZ", "F"),), emotions=("NE",), texts=1, duration_s=(1.0, 1.0), seed=2)[0]


def _layout(tmp_path, base="ag501"):
    p = tmp_path / f"{base}.layout"
    p.write_text(layout_text(base=base))
    return p


def test_ag501_rms_is_read_per_kept_sensor_and_unused_channels_are_not_measured(tmp_path, sweep):
    p = write_pos(tmp_path / "XYZFNE01.pos", sweep)
    c = read_corpus(p, layout=str(_layout(tmp_path)))
    assert c.point_names == ["NOSE", "LMA", "RMA", "UL", "LL", "LC", "RC"]  # lips, corners, references
    measure, Q = sensor_quality(c)
    assert measure == "rms" and Q.shape == (c.n_frames, 7)
    np.testing.assert_allclose(Q[:, 3], sweep.rms[:, SOCKETS.index("UL")], rtol=1e-6)
    every = read_pos(p)  # built-in layout: all 16 channels; the 6 unused ones (rms 0) are not measured
    assert np.isnan(sensor_quality(every)[1][:, 10:]).all() and np.isfinite(sensor_quality(every)[1][:, :10]).all()


def test_ag500_headerless_pos_keeps_its_rms_too(tmp_path, sweep):
    (tmp_path / "s.pos").write_bytes(pos_bytes(sweep.positions, sweep.rms, channels=12, header=False))
    c = read_corpus(tmp_path / "s.pos", layout=str(_layout(tmp_path, "ag500")))
    assert c.rate == 200 and sensor_quality(c)[0] == "rms"
    np.testing.assert_allclose(sensor_quality(c)[1][:, c.point_names.index("LL")],
                               sweep.rms[:, SOCKETS.index("LL")], rtol=1e-6)


def test_an_out_of_range_rms_is_reported_naming_sensor_and_frames_and_the_positions_kept(tmp_path, sweep):
    rms = sweep.rms.copy()
    i = SOCKETS.index("LL")
    rms[40:43, i] = -1.0
    rms[90, i] = np.nan
    p = tmp_path / "bad.pos"
    p.write_bytes(pos_bytes(sweep.positions, rms))
    with collecting_repairs() as notes:
        c = read_corpus(p, layout=str(_layout(tmp_path)))
    (line,) = [n for n in notes if "rms is out of range" in n]
    assert "bad.pos: LL rms is out of range (-1 in frames 40-42, 90" in line and "4 quality values" in line
    q = sensor_quality(c)[1][:, c.point_names.index("LL")]
    assert np.isnan(q[[40, 41, 42, 90]]).all() and np.isfinite(q[:40]).all()
    np.testing.assert_allclose(c.frames[41, 12:15], sweep.positions[41, i], atol=1e-4)  # position kept


def test_ndi_wave_state_and_error_columns(tmp_path, sweep):
    X = sweep.positions[:120:2, :4]  # 100 Hz, four sensors
    err = np.full(X.shape[:2], 0.4)
    err[10:14, 3] = 2.5
    state = np.full(X.shape[:2], "OK", dtype=object)
    state[20, 1] = "Missing"
    (tmp_path / "w.tsv").write_text(wave_tsv(X, state=state, error=err))
    c = read_wave(tmp_path / "w.tsv")
    assert c.rate == 100 and c.n_points == 4
    measure, Q = sensor_quality(c)
    assert measure == "error" and Q[12, 3] == pytest.approx(2.5) and np.isnan(Q[20, 1])  # no position, no quality
    np.testing.assert_allclose(c.frames[20, 3:6], 0.5 * (X[19, 1] + X[21, 1]), atol=1e-3)  # the dropout filled
    assert any("status not OK" in h for h in c.history)


def _one(rms, rate=100.0):
    """A 2-point corpus whose point 0 moves linearly, with quality ``rms`` (n, 2)."""
    from engine.recordings.corpus import Corpus, Utterance

    n = len(rms)
    F = np.zeros((n, 6), np.float32)
    F[:, 0] = np.arange(n)
    F[:, 4] = 5.0
    return Corpus(frames=F, rate=rate, utterances=[Utterance("u", 0, n)], point_names=["UL", "LL"],
                  latent={"quality_rms": np.asarray(rms, np.float32)})


def test_rows_give_share_and_longest_run_computed_by_hand():
    rms = np.ones((50, 2))
    rms[5:8, 0] = 9.0   # 3 frames
    rms[20:30, 0] = 9.0  # 10 frames: the longest
    rms[40, 0] = 0.0     # not measured
    (ul, ll) = quality_rows(_one(rms), threshold=4.0)
    assert ul["frames"] == 49 and ul["share_above"] == pytest.approx(13 / 49)
    assert ul["longest_run_frames"] == 10 and ul["longest_run_s"] == pytest.approx(0.1) and ul["runs_above"] == 2
    assert ll["share_above"] == 0 and ll["median"] == 1.0
    starts, lengths = runs_of(rms[:, 0] > 4)
    assert starts.tolist() == [5, 20] and lengths.tolist() == [3, 10]


def test_mask_interpolates_short_runs_linearly_and_leaves_long_ones_named():
    rms = np.ones((50, 2))
    rms[5:8, 0] = 9.0
    rms[20:30, 0] = 9.0
    c = _one(rms)
    F = np.array(c.frames)
    F[5:8, 1] = 99.0  # a jump during the short burst
    c = type(c)(frames=F, rate=c.rate, utterances=c.utterances, point_names=c.point_names, latent=c.latent)
    res = apply_quality(c, 4.0, QualityPolicy(action="mask", max_gap_s=0.05))
    out = np.asarray(res.corpus.frames)
    np.testing.assert_allclose(out[5:8, 1], 0.0)  # between the neighbours (0 and 0)
    np.testing.assert_allclose(out[5:8, 0], [5, 6, 7])  # a line through the neighbours 4 and 8
    np.testing.assert_array_equal(out[20:30], F[20:30])  # 100 ms > 50 ms: left as recorded
    assert res.interpolated == 3 and res.long_runs == {"u": ["UL 0.100 s from 0.200 s"]}
    line = action_line([res], 4.0, QualityPolicy(action="mask"), rate=c.rate)
    assert "3 samples in runs of at most 5 frames (50 ms)" in line
    assert "left as recorded in 1 utterance(s): u (UL" in line


def test_drop_leaves_out_utterances_with_long_runs_and_keep_changes_nothing():
    from engine.io import concat

    rms_bad, rms_good = np.ones((50, 2)), np.ones((40, 2))
    rms_bad[10:30, 1] = 9.0
    a, b = _one(rms_bad), _one(rms_good)
    from dataclasses import replace

    b = replace(b, utterances=[replace(b.utterances[0], id="v")])
    c = concat([a, b])
    res = apply_quality(c, 4.0, QualityPolicy(action="drop"))
    assert [u.id for u in res.corpus.utterances] == ["v"] and res.dropped == ["u"]
    kept = apply_quality(c, 4.0, QualityPolicy(action="keep"))
    assert kept.corpus is c and kept.rows[0]["action"] == "keep"
    only_bad = apply_quality(a, 4.0, QualityPolicy(action="drop"))
    assert only_bad.corpus is None


def test_default_threshold_is_relative_and_the_summary_names_the_bad_speaker(tmp_path):
    from dataclasses import replace

    from engine.recordings.metadata import with_fields

    parts = []
    for spk, r in (("XYZ", 8.6), ("ABC", 1.0), ("DEF", 1.0)):
        rms = np.full((60, 2), 1.0)
        rms[:, 0] = r
        c = _one(rms)
        parts.append(replace(c, utterances=[with_fields(replace(c.utterances[0], id=f"{spk}01"), {"speaker": spk})]))
    th, how = resolve_threshold(parts, QualityPolicy())
    assert th == pytest.approx(3.0) and "3 x the median 1" in how
    assert resolve_threshold(parts, QualityPolicy(threshold=10))[0] == 10
    rows = [r for c in parts for r in quality_rows(c, th)]
    lines = summary_lines(rows, th, how, speakers={c.utterances[0].id: c.utterances[0].speaker for c in parts})
    (ul,) = [x for x in lines if x.startswith("quality: UL")]
    assert "speaker XYZ median 8.6, 100.0% of samples above in 1 of 1 utterances" in ul
    assert "speaker ABC median 1, 0.0% of samples above" in ul
    assert lines[-1] == "quality: no rms above 3 in LL (median 1)"


@pytest.mark.parametrize("kw, message", [
    (dict(action="delete"), "expected one of keep, mask, drop"),
    (dict(threshold=-2), "expected a positive number"),
    (dict(max_gap_s=5), "expected 0 to 1 s"),
])
def test_a_policy_that_cannot_be_followed_is_refused(kw, message):
    with pytest.raises(ValueError, match=message):
        QualityPolicy(**kw)


def test_resampling_keeps_the_quality_values(sweep, tmp_path):
    from engine.io import resample

    c = read_corpus(write_pos(tmp_path / "a.pos", sweep), layout=str(_layout(tmp_path)))
    r = resample(c, 60.0)
    assert sensor_quality(r)[1].shape == (r.n_frames, r.n_points)


def test_the_real_ag501_sweeps_report_their_rms(shared_data):
    c = read_pos(shared_data / "ag501-greek" / "0021.pos")
    measure, Q = sensor_quality(c)
    active = np.isfinite(Q).any(axis=0)
    assert measure == "rms" and active.sum() == 8 and active[:8].all()  # eight channels named in the header
    rows = quality_rows(c, 20.0)
    assert len(rows) == 8 and all(r["share_above"] == 0 for r in rows)
