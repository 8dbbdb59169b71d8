"""Plain numeric matrices through sensor layouts: .mat, .npy, CSV without names, .pos, NDI Wave TSV."""
import numpy as np
import pytest

from engine.io import ImportFormatError, read_corpus
from engine.io.readers.articulograph import read_pos, read_wave
from engine.io.readers.matrix import read_matrix
from engine.recordings.layouts import BUILTIN, LayoutError, guess_roles, read_layout
from engine.talker.multispeaker import generate_recordings, layout_text


@pytest.fixture(scope="module")
def rec():
    return generate_recordings(n_speakers=1, n_utterances=1, duration_s=(0.6, 0.6), seed=3)[0]


def _check_7x6(c, rec, n_frames=None):
    assert c.point_names == ["UL", "LL", "LC", "RC"]  # tongue left out by default
    assert c.point_roles == ["upper_lip", "lower_lip", "left_corner", "right_corner"]
    n = n_frames or rec.matrix.shape[0]
    assert c.n_frames == n and c.dims == 3
    np.testing.assert_allclose(c.frames[:, :3], rec.matrix[:n, 0:3], rtol=1e-5, atol=1e-5)  # UL x y z
    np.testing.assert_allclose(c.frames[:, 3:6], rec.matrix[:n, 6:9], rtol=1e-5, atol=1e-5)  # LL x y z


def test_mat_npy_csv_with_builtin_7x6_layout(tmp_path, rec):
    import scipy.io

    scipy.io.savemat(tmp_path / "u.mat", {"data": rec.matrix, "fs": 250.0})
    c = read_corpus(tmp_path / "u.mat", layout="ema7x6")  # rate from the fs variable
    assert c.rate == 250
    _check_7x6(c, rec)
    np.save(tmp_path / "u.npy", rec.matrix)
    _check_7x6(read_corpus(tmp_path / "u.npy", layout="ema7x6", rate=250), rec)
    np.savetxt(tmp_path / "u.csv", rec.matrix, delimiter=",", fmt="%.6f")
    _check_7x6(read_corpus(tmp_path / "u.csv", layout="ema7x6", rate=250), rec)
    c = read_corpus(tmp_path / "u.csv", layout="ema7x6", rate=250, points="all")
    assert c.n_points == 7 and c.point_roles[4:] == ["tongue"] * 3
    c = read_corpus(tmp_path / "u.csv", layout="ema7x6", rate=250, points=["ll", "UL"])
    assert c.point_names == ["LL", "UL"]


def test_matrix_errors_name_the_fix(tmp_path, rec):
    np.save(tmp_path / "u.npy", rec.matrix[:, :40])
    with pytest.raises(ImportFormatError, match=r"40 columns but layout 'ema7x6' expects 7 sensors x 6 values = 42$"):
        read_matrix(tmp_path / "u.npy", layout="ema7x6", rate=250)
    np.save(tmp_path / "v.npy", rec.matrix)
    with pytest.raises(ImportFormatError, match=r"no timing.*--rate HZ"):
        read_matrix(tmp_path / "v.npy", layout="ema7x6")
    with pytest.raises(ImportFormatError, match=r"no sensor 'NOSE'.*UL, LL"):
        read_matrix(tmp_path / "v.npy", layout="ema7x6", rate=250, points=["UL", "NOSE"])
    (tmp_path / "r.csv").write_text("1,2,3\n4,5\n")
    with pytest.raises(ImportFormatError, match=r"r.csv, line 2: has 2 values; earlier lines have 3"):
        read_matrix(tmp_path / "r.csv", layout="ema7x6", rate=250)
    (tmp_path / "h.csv").write_text("UL_x,UL_y\n1,2\n")
    with pytest.raises(ImportFormatError, match=r"line 1.*column names.*without --layout"):
        read_matrix(tmp_path / "h.csv", layout="ema7x6", rate=250)
    # a plain matrix given to the MVIEW reader points at --layout
    import scipy.io

    scipy.io.savemat(tmp_path / "X.mat", {"X": rec.matrix})
    with pytest.raises(ImportFormatError, match=r"plain \d+ x 42 numeric matrix.*--layout ema7x6"):
        read_corpus(tmp_path / "X.mat")


def test_user_layout_file_and_its_errors(tmp_path):
    f = tmp_path / "lab.layout"
    f.write_text(layout_text(reference=True))
    lay = read_layout(f)
    assert lay.sensors[-3:] == ("NOSE", "LMA", "RMA") and lay.roles[-1] == "reference" and lay.values == 6
    assert lay.select(None) == [0, 1, 2, 3, 7, 8, 9]  # lips + reference, no tongue
    bad = tmp_path / "bad.layout"
    bad.write_text("values: 6\nsensor UL upper_lip\nsensor LL mouth\n")
    with pytest.raises(LayoutError, match=r"bad.layout, line 3: role 'mouth'; expected one of upper_lip"):
        read_layout(bad)
    bad.write_text("values: 6\nxyz: 0 1 9\nsensor UL upper_lip\n")
    with pytest.raises(LayoutError, match=r"xyz=\(0, 1, 9\)"):
        read_layout(bad)
    assert guess_roles(["UL", "LL", "ML", "JAW", "TT", "T3", "REF", "xx"]) == [
        "upper_lip", "lower_lip", "left_corner", "jaw", "tongue", "tongue", "reference", ""]


def _pos_bytes(M, n_ch, header=True, rate=250):
    body = M.astype("<f4").tobytes()
    if not header:
        return body
    text = f"NumberOfChannels={n_ch}\nSamplingFrequencyHz={rate}\n"
    head = b"AG50xDATA_V002\n"
    size = len(head) + 9 + len(text)
    return head + f"{size:08d}\n".encode() + text.encode() + body


def test_ag501_and_ag500_pos(tmp_path, rec):
    n = rec.matrix.shape[0]
    M7 = np.zeros((n, 7, 7))
    M7[:, :, :6] = rec.matrix.reshape(n, 7, 6)
    (tmp_path / "a.pos").write_bytes(_pos_bytes(M7.reshape(n, -1), 7))
    lay = tmp_path / "ag.layout"
    lay.write_text("base: ag501\n" + "\n".join(f"sensor {s} {r}" for s, r in zip(BUILTIN["ema7x6"].sensors,
                                                                                  BUILTIN["ema7x6"].roles)) + "\n")
    c = read_corpus(tmp_path / "a.pos", layout=str(lay))
    assert c.rate == 250
    _check_7x6(c, rec)
    c = read_pos(tmp_path / "a.pos")  # built-in: generic channel names, every channel
    assert c.point_names == [f"ch{i + 1}" for i in range(7)] and c.point_roles is None
    # AG500: no header, 12 channels at 200 Hz
    M12 = np.zeros((n, 12, 7))
    M12[:, :7] = M7
    (tmp_path / "b.pos").write_bytes(_pos_bytes(M12.reshape(n, -1), 12, header=False))
    c = read_corpus(tmp_path / "b.pos", layout="ag500")
    assert c.rate == 200 and c.n_points == 12
    (tmp_path / "t.pos").write_bytes(_pos_bytes(M12.reshape(n, -1), 12, header=False)[:-10])
    with pytest.raises(ImportFormatError, match=r"not a whole number of frames"):
        read_pos(tmp_path / "t.pos", layout="ag500")


def test_ndi_wave_tsv_with_dropout(tmp_path, rec):
    n = 40
    X = rec.matrix.reshape(-1, 7, 6)[:n, :, :3]
    head = ["Time", "MeasId"]
    for k in range(7):
        head += [f"Sensor {k + 1} Id", "Status", "Tx", "Ty", "Tz", "Q0", "Qx", "Qy", "Qz"]
    lines = ["\t".join(head)]
    for i in range(n):
        row = [f"{i / 100:.3f}", str(i)]
        for k in range(7):
            st = "Missing" if (i == 5 and k == 1) else "OK"
            row += [str(k + 1), st, *(f"{v:.4f}" for v in X[i, k]), "1", "0", "0", "0"]
        lines.append("\t".join(row))
    (tmp_path / "w.tsv").write_text("\n".join(lines) + "\n")
    lay = tmp_path / "w.layout"
    lay.write_text("base: wave\n" + "\n".join(f"sensor {s} {r}" for s, r in zip(BUILTIN["ema7x6"].sensors,
                                                                                 BUILTIN["ema7x6"].roles)) + "\n")
    c = read_wave(tmp_path / "w.tsv", layout=str(lay))
    assert c.rate == 100 and c.point_names == ["UL", "LL", "LC", "RC"]
    np.testing.assert_allclose(c.frames[4, 3:6], X[4, 1], atol=1e-3)
    np.testing.assert_allclose(c.frames[5, 3:6], 0.5 * (X[4, 1] + X[6, 1]), atol=1e-3)  # dropout interpolated
    with pytest.raises(ImportFormatError, match=r"frame 5"):
        read_wave(tmp_path / "w.tsv", layout=str(lay), fill_gaps=False)
    c = read_corpus(tmp_path / "w.tsv", format="wave")
    assert c.n_points == 7 and c.point_names[0] == "ch1"
