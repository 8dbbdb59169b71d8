"""Every data defect a file can carry is repaired and reported per file (in the corpus history), or refused
naming the file, the field and the frame: dropouts, break flags, non-finite and implausible values, rates
that are zero, non-finite or absurd, duplicated or missing columns, counts that disagree with the body."""
import math
import re

import numpy as np
import pytest
import scipy.io
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_io_c3d import _write as _write_c3d  # the C3D writer of the reader's own tests (rate, labels, invalid)

from engine.io import (
    ImportFormatError,
    read_c3d,
    read_corpus,
    read_csv_landmarks,
    read_ema,
    read_mview,
    read_pos,
    read_textgrid,
    read_wave,
    write_audio,
    write_est_track,
    write_mesh_sequence,
    write_ply,
)
from engine.io._util import IMPLAUSIBLE_COORDINATE, MAX_FILL_FRACTION, fill_gaps
from engine.io.errors import ImportDataWarning
from engine.io.repairs import collecting_repairs, frame_runs, report_repair

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def _notes(corpus, needle=""):
    return [h for h in corpus.history if needle in h]


# ------------------------------------------------------------------ the report itself
def test_fill_gaps_reports_what_where_and_how():
    X = np.tile(np.arange(10.0)[:, None], (1, 3))
    X[2, 0], X[3, 0], X[7, 1] = np.nan, np.inf, 5e7
    flag = np.zeros(10, bool)
    flag[0] = True
    with collecting_repairs() as notes:
        out = fill_gaps(X, flag, path="f.csv", names=["a_x", "a_y", "b_x"], flagged="success 0")
    assert np.isfinite(out).all() and abs(out[7, 1] - 7) < 1e-6 and abs(out[2, 0] - 2) < 1e-6
    (line,) = notes
    assert line.startswith("f.csv: ")
    for part in ("6 missing samples", "3 success 0", "1 NaN", "1 infinite", "1 implausibly large",
                 "a_x, a_y, b_x", "4 of 10 frames", "frames 0, 2, 3, 7", "interpolated linearly",
                 "holds its first or last valid value"):
        assert part in line, (part, line)


def test_fill_gaps_refuses_what_it_cannot_honestly_repair():
    X = np.zeros((10, 2))
    X[:6, 1] = np.nan  # 60 % of one channel
    with pytest.raises(ImportFormatError, match=r"b is missing in 6 of 10 frames \(60%: 6 NaN\); at most 50%") as e:
        fill_gaps(X, np.zeros(10, bool), path="p.pos", names=["a", "b"])
    assert e.value.frame == 0 and e.value.path == "p.pos"
    X[:, 1] = np.nan
    with pytest.raises(ImportFormatError, match="b is missing in every frame"):
        fill_gaps(X, np.zeros(10, bool), path="p.pos", names=["a", "b"])
    Y = np.zeros((10, 1))
    Y[4] = np.nan
    with pytest.raises(ImportFormatError, match=r"gap filling is off \(import without --no-fill") as e:
        fill_gaps(Y, np.zeros(10, bool), path="p.pos", fill=False)
    assert e.value.frame == 4 and "fill_gaps" not in str(e.value)
    assert MAX_FILL_FRACTION == 0.5


def test_a_repair_outside_a_reader_is_a_warning():
    with pytest.warns(ImportDataWarning, match="x.wav: something"):
        report_repair("x.wav", "something")
    with collecting_repairs() as outer, collecting_repairs() as inner:
        report_repair("y", "z")
    assert outer == inner == ["y: z"]
    assert frame_runs([7, 8, 20, 21, 22, 30]) == "frames 7, 8, 20-22, 30"
    assert frame_runs(range(0, 40, 2), limit=3) == "frames 0, 2, 4 and 17 more runs"


# ------------------------------------------------------------------ every reader repairs and says so
def test_csv_nan_inf_and_empty_cells_are_reported(tmp_path):
    p = tmp_path / "holes.csv"
    holes = {(10, 0): "", (11, 0): "", (20, 1): "nan", (30, 2): "inf"}  # (frame, column): what the cell holds
    X = np.column_stack([np.sin(np.arange(50) / 5), np.full((50, 3), [2.0, 3.0, 4.0])])
    cells = [[holes.get((k, j), f"{v:.4f}") for j, v in enumerate(row)] for k, row in enumerate(X)]
    p.write_text("time,UL_x,UL_y,LL_x,LL_y\n" + "".join(f"{k / 100:.2f},{','.join(r)}\n" for k, r in enumerate(cells)))
    c = read_csv_landmarks(p)
    (note,) = _notes(c, "missing samples")
    assert "3 empty or NaN, 1 infinite" in note and "frames 10, 11, 20, 30" in note and str(p) in note
    assert read_corpus(p).history == c.history  # the dispatcher keeps it too


def test_openface_unsuccessful_rows_and_other_faces_are_reported(tmp_path):
    def openface(rows):  # frame, face_id, success per row; two landmarks
        p = tmp_path / "of.csv"
        p.write_text("frame, face_id, timestamp, success, x_0, x_1, y_0, y_1\n" + "".join(
            f"{f}, {face}, {f / 30:.3f}, {ok}, {k}, {k}, 1, 2\n" for k, (f, face, ok) in enumerate(rows)))
        return read_csv_landmarks(p)

    (note,) = _notes(openface([(k + 1, 0, int(k not in (4, 5))) for k in range(30)]), "missing samples")
    assert "8 success 0" in note and "frames 4, 5" in note
    (note,) = _notes(openface([(k // 2 + 1, k % 2, 1) for k in range(40)]), "other faces")
    assert "20 rows of other faces (face_id 1) left out; face_id 0 is read" in note


def test_ema_break_flags_are_reported(tmp_path):
    t = np.arange(50) / 500.0
    valid = np.ones(50, bool)
    valid[[10, 11, 12]] = False
    p = write_est_track(tmp_path / "b.ema", t, np.random.default_rng(0).normal(size=(50, 4)) * 100,
                        ["ul_x", "ul_y", "ll_x", "ll_y"], valid=valid)
    (note,) = _notes(read_ema(p, sensors=("UL", "LL")), "missing samples")
    assert "12 break flag 0" in note and "frames 10-12" in note and "UL_x, UL_y, LL_x, LL_y" in note


def test_c3d_invalid_markers_and_clashing_labels_are_reported(tmp_path):
    P = np.random.default_rng(1).normal(size=(30, 3, 3)).astype(np.float32)
    c = read_c3d(_write_c3d(tmp_path / "m.c3d", P, labels=["A", "B", "A"], invalid=[(5, 1), (6, 1)]))
    assert "6 marked invalid (negative residual)" in _notes(c, "missing samples")[0]
    assert c.point_names == ["A#0", "B#1", "A#2"] and _notes(c, "share the label(s) 'A'")


def _mview_file(path, ul, *, srate=100.0, names=("UL", "LL"), audio=None, audio_rate=44100.0):
    dt = [("NAME", "O"), ("SRATE", "O"), ("SIGNAL", "O"), ("SENTENCE", "O"), ("PHONES", "O")]
    s = np.zeros((1, 1 + len(names)), dtype=dt)
    snd = np.random.default_rng(2).normal(size=(1000, 1)) if audio is None else audio
    s[0, 0] = ("AUDIO", audio_rate, snd.astype(np.float32), "", np.zeros((0, 0)))
    for k, n in enumerate(names):
        s[0, 1 + k] = (n, srate, ul.astype(np.float32) + k, "", np.zeros((0, 0)))
    scipy.io.savemat(path, {path.stem: s})
    return path


def test_haskins_nan_samples_are_reported(tmp_path):
    sig = np.random.default_rng(3).normal(size=(40, 6))
    sig[[3, 4], 0] = np.nan
    c = read_mview(_mview_file(tmp_path / "h.mat", sig), sensors=("UL", "LL"))
    (note,) = _notes(c, "missing samples")
    assert "4 NaN" in note and "UL_x, LL_x" in note and "frames 3, 4" in note


def _pos_file(path, M, rate="250", n_ch=2):
    hdr = f"AG50xDATA_V002\n00000000\nNumberOfChannels={n_ch}\nSamplingFrequencyHz={rate}\n".encode()
    hdr = hdr.replace(b"00000000", f"{len(hdr):08d}".encode())
    path.write_bytes(hdr + np.asarray(M, "<f4").tobytes())
    return path


def test_pos_nan_is_reported_below_half_and_refused_above(tmp_path):
    M = np.random.default_rng(4).normal(size=(100, 14))
    M[:20] = np.nan
    c = read_pos(_pos_file(tmp_path / "a.pos", M), layout="ag501")
    assert "frames 0-19" in _notes(c, "missing samples")[0]
    M[:60] = np.nan  # the campaign's .pos that is 60 % NaN: no longer interpolated without a word
    with pytest.raises(ImportFormatError, match=r"missing in 60 of 100 frames \(60%"):
        read_pos(_pos_file(tmp_path / "b.pos", M), layout="ag501")


def test_wave_status_and_mesh_nan_and_implausible_values_are_reported(tmp_path):
    head = "Time\tSensor 1 Id\tSensor 1 Status\tSensor 1 Tx\tSensor 1 Ty\tSensor 1 Tz"
    rows = [f"{k / 100:.2f}\t1\t{'Missing' if k == 7 else 'OK'}\t{k}\t1\t{2e9 if k == 9 else 2}" for k in range(30)]
    p = tmp_path / "w.tsv"
    p.write_text(head + "\n" + "\n".join(rows) + "\n")
    note = _notes(read_wave(p), "missing samples")[0]
    assert "3 status not OK" in note and "1 implausibly large" in note and "frames 7, 9" in note
    P = np.random.default_rng(5).normal(size=(6, 4, 3))
    P[2, 1, 0] = np.nan
    write_mesh_sequence(tmp_path / "seq", P, format="ply")
    note = _notes(read_corpus(tmp_path / "seq", rate=30), "missing samples")[0]
    assert "vertex 1 x" in note and "frames 2" not in note and "frame 2" in note
    assert IMPLAUSIBLE_COORDINATE == 1e6


# ------------------------------------------------------------------ rates: zero, non-finite, absurd
@pytest.mark.parametrize("value, match", [("0", "SamplingFrequencyHz is 0; expected a frame rate"),
                                          ("1e300", "SamplingFrequencyHz is 1e\\+300 Hz; a frame rate"),
                                          ("NaN", "SamplingFrequencyHz is nan"),
                                          ("-250", "SamplingFrequencyHz is -250"),
                                          ("fast", "SamplingFrequencyHz is 'fast'")])
def test_pos_header_rates_are_checked(tmp_path, value, match):
    M = np.random.default_rng(6).normal(size=(50, 14))
    with pytest.raises(ImportFormatError, match=match) as e:
        read_pos(_pos_file(tmp_path / "r.pos", M, rate=value), layout="ag501")
    assert e.value.line == 4


def test_every_header_rate_goes_through_one_check(tmp_path):
    sig = np.random.default_rng(7).normal(size=(40, 6))
    for srate in (0.0, 1e300, np.nan, 1e5):
        with pytest.raises(ImportFormatError, match=r"entry 2 \(UL\) SRATE is"):
            read_mview(_mview_file(tmp_path / "h.mat", sig, srate=srate), sensors=("UL",))
    P = np.random.default_rng(8).normal(size=(10, 2, 3)).astype(np.float32)
    with pytest.raises(ImportFormatError, match="POINT:RATE is 1e\\+06 Hz"):
        read_c3d(_write_c3d(tmp_path / "r.c3d", P, rate=1e6))
    scipy.io.savemat(tmp_path / "m.mat", {"data": np.zeros((20, 42)), "fs": np.array([[0.0]])})
    with pytest.raises(ImportFormatError, match="variable 'fs' is 0"):
        read_corpus(tmp_path / "m.mat", layout="ema7x6")
    p = tmp_path / "slow.csv"
    p.write_text("time,a_x,a_y\n" + "".join(f"{k},{k},0\n" for k in range(20)))  # times in frames, not seconds
    with pytest.raises(ImportFormatError, match=r"the frame times \(a step of 1 s\) give a rate that is 1 Hz"):
        read_corpus(p)
    write_mesh_sequence(tmp_path / "seq", np.zeros((3, 3, 3)))
    with pytest.raises(ImportFormatError, match=r"the frame rate given \(--rate\) is 1e\+09 Hz"):
        read_corpus(tmp_path / "seq", rate=1e9)


def test_audio_rates_and_non_finite_samples(tmp_path):
    sig = np.random.default_rng(9).normal(size=(40, 6))
    snd = np.random.default_rng(9).normal(size=(4410, 1)) * 0.1
    snd[100:110] = np.nan
    src = _mview_file(tmp_path / "a.mat", sig, audio=snd)
    with collecting_repairs() as notes:
        wav = write_audio(src, tmp_path / "a.wav")
    rate, x = scipy.io.wavfile.read(wav)
    assert rate == 44100 and (x[100:110] == 0).all() and np.abs(x).max() < 32767
    assert notes and "10 of 4410 samples are not finite" in notes[0] and "written as silence" in notes[0]
    src = _mview_file(tmp_path / "b.mat", sig, audio=np.full((4410, 1), np.inf))
    with pytest.raises(ImportFormatError, match="AUDIO signal has no finite sample"):
        write_audio(src, tmp_path / "b.wav")  # not a full-scale DC file
    assert not (tmp_path / "b.wav").exists()
    src = _mview_file(tmp_path / "c.mat", sig, audio_rate=1e300)
    with pytest.raises(ImportFormatError, match=r"entry 1 \(AUDIO\) SRATE is 1e\+300 Hz; a sample rate"):
        write_audio(src, tmp_path / "c.wav")


# ------------------------------------------------------------------ duplicated and missing columns
def test_csv_duplicated_and_missing_columns_are_refused(tmp_path):
    p = tmp_path / "d.csv"
    p.write_text("time,UL_x,UL_y,UL_x,LL_y\n" + "".join(f"{k / 100},1,2,3,4\n" for k in range(20)))
    with pytest.raises(ImportFormatError, match=r"columns 2 \('UL_x'\) and 4 \('UL_x'\) name the same"):
        read_csv_landmarks(p)
    p.write_text("time,UL_x,UL_y,LL_y\n" + "".join(f"{k / 100},1,2,4\n" for k in range(20)))
    with pytest.raises(ImportFormatError, match=r"point 'LL' has column\(s\) 'LL_y' but no LL_x column"):
        read_csv_landmarks(p)  # the lower lip was dropped without a word
    p.write_text("time,x_0,x_0,y_0\n" + "".join(f"{k / 100},1,2,4\n" for k in range(20)))
    with pytest.raises(ImportFormatError, match="name the same coordinate"):
        read_csv_landmarks(p)


def test_est_and_mview_duplicated_names_are_refused(tmp_path):
    t = np.arange(20) / 500.0
    v = np.zeros((20, 4))
    p = write_est_track(tmp_path / "d.ema", t, v, ["ul_x", "ul_y", "ul_x", "ll_y"])
    with pytest.raises(ImportFormatError, match=r"channels 0 \('ul_x'\) and 2 \('ul_x'\) are both sensor UL's x"):
        read_ema(p, sensors=("UL",))
    p = write_est_track(tmp_path / "h.ema", t, v, ["ul_x", "ul_y", "ll_y", "jaw_y"])
    with pytest.raises(ImportFormatError, match=r"sensor LL has an y channel \('ll_y', channel 2\) but no x"):
        read_ema(p, sensors=("UL", "LL"))
    sig = np.random.default_rng(10).normal(size=(30, 6))
    with pytest.raises(ImportFormatError, match="entries 2 and 3 are both named 'UL'"):
        read_mview(_mview_file(tmp_path / "h.mat", sig, names=("UL", "UL")), sensors=("UL",))


# ------------------------------------------------------------------ counts that disagree with the body
def _long_textgrid(declared, intervals, tiers_declared=1, tiers=1):
    out = ['File type = "ooTextFile"', 'Object class = "TextGrid"', "", "xmin = 0", "xmax = 1", "tiers? <exists>",
           f"size = {tiers_declared}", "item []:"]
    for t in range(tiers):
        out += [f"    item [{t + 1}]:", '        class = "IntervalTier"', f'        name = "phones{t or ""}"',
                "        xmin = 0", "        xmax = 1", f"        intervals: size = {declared}"]
        for k in range(intervals):
            out += [f"        intervals [{k + 1}]:", f"            xmin = {k / intervals}",
                    f"            xmax = {(k + 1) / intervals}", f'            text = "p{k}"']
    return "\n".join(out) + "\n"


def test_textgrid_counts_smaller_than_the_body_are_refused(tmp_path):
    p = tmp_path / "a.TextGrid"
    p.write_text(_long_textgrid(5, 5))
    assert len(read_textgrid(p)) == 5
    p.write_text(_long_textgrid(2, 5))  # the campaign's: 'size = 2' before 5 intervals kept 2
    with pytest.raises(ImportFormatError, match=r"line 23: not a valid TextGrid: found 'intervals \[3\]:'") as e:
        read_textgrid(p)
    assert "count" in str(e.value)
    p.write_text(_long_textgrid(2, 2, tiers_declared=1, tiers=2))
    with pytest.raises(ImportFormatError, match="item \\[2\\]"):
        read_textgrid(p)
    short = ('File type = "ooTextFile"\nObject class = "TextGrid"\n\n0\n1\n<exists>\n1\n"IntervalTier"\n"phones"\n'
             '0\n1\n1\n0\n0.5\n"a"\n0.5\n1\n"b"\n')
    p.write_text(short)
    with pytest.raises(ImportFormatError, match=r"line 16: .*found '0.5' after the last item"):
        read_textgrid(p)


def test_ply_counts_smaller_than_the_body_are_refused(tmp_path):
    p = write_ply(tmp_path / "a.ply", np.eye(3), [[0, 1, 2]])
    p.write_bytes(p.read_bytes() + b"0 0 1\n")
    with pytest.raises(ImportFormatError, match=r"1 more line\(s\) follow the rows the header's element counts"):
        read_corpus([p, p], format="mesh", rate=30)
    b = write_ply(tmp_path / "b.ply", np.eye(3), [[0, 1, 2]], binary=True)
    b.write_bytes(b.read_bytes() + np.zeros(3, "<f4").tobytes() + b"\x01")
    with pytest.raises(ImportFormatError, match="bytes follow the rows"):
        read_corpus([b, b], format="mesh", rate=30)


# ------------------------------------------------------------------ hypothesis: the parsers' numeric fields
_number_text = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64).map(repr),
    st.sampled_from(["", "nan", "NaN", "inf", "-inf", "1e308", "1e309", "-0", "1e-320", "0x10", "1,5", "abc"]),
    st.integers(-10**12, 10**12).map(str))


@SETTINGS
@given(st.lists(_number_text, min_size=8, max_size=8))
def test_csv_cells_are_read_reported_or_refused(tmp_path, cells):
    """Any text in a CSV cell: the import is refused naming the line, or every sample that was not a plausible
    number is counted in the history; the frames are finite either way."""
    rows = ["time,a_x,a_y"] + [f"{k / 100:.2f},{k},{k}" for k in range(40)]
    for k, cell in enumerate(cells):
        r = 1 + 5 * k
        rows[r] = f"{(r - 1) / 100:.2f},{cell},{r}"
    p = tmp_path / "h.csv"
    p.write_text("\n".join(rows) + "\n")
    try:
        c = read_csv_landmarks(p)
    except ImportFormatError as exc:
        assert str(p) in str(exc) and (exc.line is not None or "missing" in str(exc)), exc
        return
    assert np.isfinite(c.frames).all()
    bad = 0
    for cell in cells:
        try:
            v = float(cell) if cell.strip() else math.nan
        except ValueError:
            pytest.fail(f"{cell!r} was read as a number")
        bad += not (math.isfinite(v) and abs(v) <= IMPLAUSIBLE_COORDINATE)
    notes = _notes(c, "missing samples")
    if bad:
        assert notes and re.match(rf".*: {bad} missing samples", notes[0]), (cells, notes)
    else:
        assert not notes


@SETTINGS
@given(st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                 st.sampled_from(["", "0", "-1", "abc", "1e300", "250.0.0", "1e-300"])))
def test_pos_sampling_frequency_is_in_range_or_refused_by_name(tmp_path, value):
    M = np.random.default_rng(11).normal(size=(30, 14))
    try:
        c = read_pos(_pos_file(tmp_path / "r.pos", M, rate=value), layout="ag501")
    except ImportFormatError as exc:
        assert "SamplingFrequencyHz is" in str(exc) and exc.line == 4
        return
    assert 10 <= c.rate <= 20000 and c.rate == float(value)


@SETTINGS
@given(st.integers(-3, 40), st.integers(1, 12))
def test_textgrid_interval_counts_must_match(tmp_path, declared, held):
    p = tmp_path / "t.TextGrid"
    p.write_text(_long_textgrid(declared, held))
    try:
        phones = read_textgrid(p)
    except ImportFormatError as exc:
        assert declared != held and exc.line is not None
        return
    assert declared == held and len(phones) == held


@SETTINGS
@given(st.floats(allow_nan=True, allow_infinity=True))
def test_mview_srate_is_in_range_or_refused_by_name(tmp_path, srate):
    sig = np.random.default_rng(12).normal(size=(30, 6))
    path = tmp_path / "s.mat"
    try:
        c = read_mview(_mview_file(path, sig, srate=srate), sensors=("UL",))
    except ImportFormatError as exc:
        assert "SRATE is" in str(exc)
        return
    assert 10 <= srate <= 20000 and c.rate == srate


def test_reversed_and_zero_length_phones_are_refused_or_reported(tmp_path):
    p = tmp_path / "r.TextGrid"
    p.write_text(_long_textgrid(2, 2)
                 .replace("            xmax = 0.5\n", "            xmax = 0.25\n", 1)
                 .replace("            xmin = 0.5\n", "            xmin = 0.3\n", 1)
                 .replace("            xmax = 1.0", "            xmax = 0.28"))
    with pytest.raises(ImportFormatError, match=r"xmin > xmax"):  # a reversed interval: never dropped quietly
        read_textgrid(p)
    csv = tmp_path / "a.csv"
    csv.write_text("time,a_x,a_y\n" + "".join(f"{k / 100:.2f},{k},0\n" for k in range(50)))
    lab = tmp_path / "a.lab"
    lab.write_text("0 0.2 p\n0.2 0.2 t\n0.2 0.4 aa\n")
    (note,) = _notes(read_corpus(csv, alignment=lab), "zero duration")
    assert "1 phone of zero duration dropped from the alignment (t at 0.200 s)" in note and str(csv) in note


def test_extra_wave_fields_are_refused(tmp_path):
    w = tmp_path / "w.tsv"
    w.write_text("Time\tSensor 1 Id\tSensor 1 Tx\tSensor 1 Ty\tSensor 1 Tz\n" + "".join(
        f"{k / 100:.2f}\t1\t{k}\t1\t2{chr(9) + '7' if k == 3 else chr(9)}\n" for k in range(20)))
    with pytest.raises(ImportFormatError, match="line 5: has 6 fields; the header has 5"):
        read_wave(w)


@SETTINGS
@given(st.integers(-2, 60), st.integers(2, 40))
def test_est_frame_counts_must_match_the_body(tmp_path, declared, held):
    t = np.arange(held) / 500.0
    p = write_est_track(tmp_path / "e.ema", t, np.zeros((held, 2)), ["ul_x", "ul_y"], binary=False)
    p.write_text(p.read_text().replace(f"NumFrames {held}\n", f"NumFrames {declared}\n"))
    try:
        c = read_ema(p, sensors=("UL",))
    except ImportFormatError as exc:
        assert declared != held and str(p) in str(exc) and ("NumFrames" in str(exc) or "frames" in str(exc))
        return
    assert declared == held and c.n_frames == held
