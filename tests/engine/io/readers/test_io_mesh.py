"""OBJ / PLY files, mesh sequences (one file per frame) and VOCASET-style vertex arrays."""
import numpy as np
import pytest

from engine.io import (
    ImportFormatError,
    read_corpus,
    read_mesh_sequence,
    read_obj,
    read_ply,
    read_vertex_array,
    write_mesh_sequence,
    write_obj,
    write_ply,
)


def _grid_mesh(nx=4, ny=3, seed=0):
    rng = np.random.default_rng(seed)
    xs, ys = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float))
    V = np.column_stack([xs.ravel(), ys.ravel(), rng.normal(0, 0.1, nx * ny)])
    F = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a = j * nx + i
            F += [(a, a + 1, a + nx), (a + 1, a + nx + 1, a + nx)]
    return V, np.array(F)


@pytest.mark.parametrize("writer, reader, kw", [
    (write_obj, read_obj, {}), (write_ply, read_ply, {}), (write_ply, read_ply, {"binary": True}),
])
def test_single_file_round_trip(tmp_path, writer, reader, kw):
    V, F = _grid_mesh()
    p = writer(tmp_path / ("m" + (".ply" if reader is read_ply else ".obj")), V, F, **kw)
    V2, F2 = reader(p)
    np.testing.assert_allclose(V2, V, rtol=1e-6, atol=1e-7)
    np.testing.assert_array_equal(F2, F)
    P, none = reader(writer(tmp_path / ("p" + p.suffix), V, None, **kw))
    assert none is None and P.shape == V.shape


def test_obj_polygons_slashes_and_negative_indices(tmp_path):
    p = tmp_path / "q.obj"
    p.write_text("# quad\nv 0 0 0\nv 1 0 0\nvt 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1/1/1 2//1 3 -1\n")
    V, F = read_obj(p)
    assert V.shape == (4, 3) and F.tolist() == [[0, 1, 2], [0, 2, 3]]


def test_big_endian_ply_with_extra_properties(tmp_path):
    V, F = _grid_mesh()
    head = (f"ply\nformat binary_big_endian 1.0\ncomment x\nelement vertex {len(V)}\nproperty double x\n"
            f"property double y\nproperty double z\nproperty uchar red\nelement face {len(F)}\n"
            "property list uchar uint vertex_indices\nproperty float quality\nend_header\n").encode()
    vrec = np.empty(len(V), dtype=[("x", ">f8"), ("y", ">f8"), ("z", ">f8"), ("r", "u1")])
    vrec["x"], vrec["y"], vrec["z"], vrec["r"] = V[:, 0], V[:, 1], V[:, 2], 7
    frec = np.empty(len(F), dtype=[("n", "u1"), ("i", ">u4", (3,)), ("q", ">f4")])
    frec["n"], frec["i"], frec["q"] = 3, F, 0.5
    p = tmp_path / "be.ply"
    p.write_bytes(head + vrec.tobytes() + frec.tobytes())
    V2, F2 = read_ply(p)
    np.testing.assert_array_equal(V2, V)
    np.testing.assert_array_equal(F2, F)


@pytest.mark.parametrize("text, line, match", [
    ("v 0 0 0\nv 1 0\n", 2, "expected 'v x y z'"),
    ("v 0 0 0\nv 1 0 zero\n", 2, "expected three numbers"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, "only 3 vertices"),
    ("v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "expected at least 3"),
])
def test_obj_errors_name_the_line(tmp_path, text, line, match):
    p = tmp_path / "bad.obj"
    p.write_text(text)
    with pytest.raises(ImportFormatError, match=match) as e:
        read_obj(p)
    assert e.value.line == line


def test_ply_errors(tmp_path):
    V, F = _grid_mesh()
    p = write_ply(tmp_path / "a.ply", V, F, binary=True)
    t = tmp_path / "t.ply"
    t.write_bytes(p.read_bytes()[:-20])
    with pytest.raises(ImportFormatError, match="truncated"):
        read_ply(t)
    h = tmp_path / "h.ply"
    h.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 999999999\nproperty float x\nproperty float y\n"
                  b"property float z\nend_header\n0 0 0\n")
    with pytest.raises(ImportFormatError, match="declares 999999999 rows but only 1"):
        read_ply(h)
    a = tmp_path / "a2.ply"
    a.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                  b"property float z\nend_header\n0 0 0\n1 1\n")
    with pytest.raises(ImportFormatError, match="row 1") as e:
        read_ply(a)
    assert e.value.line == 9


def _frames(n=12, seed=1):
    V, F = _grid_mesh(seed=seed)
    t = np.arange(n)[:, None, None] / 30.0
    P = V[None] + np.array([0, 0, 1.0]) * np.sin(2 * np.pi * t + V[None, :, :1])
    return P.astype(np.float32), F


@pytest.mark.parametrize("fmt, binary", [("obj", False), ("ply", False), ("ply", True)])
def test_sequence_round_trip(tmp_path, fmt, binary):
    P, F = _frames()
    d = tmp_path / "utt1"
    files = write_mesh_sequence(d, P, faces=F, format=fmt, binary=binary)
    assert len(files) == 12 and files[0].name == f"frame_00000.{fmt}"
    (tmp_path / "utt1.lab").write_text("0 0.2 m\n0.2 0.4 a\n")
    c = read_mesh_sequence(d, rate=30)
    assert c.rate == 30 and c.n_frames == 12 and c.utterances[0].id == "utt1"
    np.testing.assert_allclose(c.frames.reshape(12, -1, 3), P, atol=1e-6)
    np.testing.assert_array_equal(c.faces, F)
    assert [p.label for p in c.utterances[0].phones] == ["m", "a"]  # sidecar <dir>.lab
    g = read_corpus(str(d / f"*.{fmt}"), rate=30, alignment=False)
    np.testing.assert_array_equal(g.frames, c.frames)


def test_sequence_order_is_natural(tmp_path):
    P, F = _frames(n=11)
    for k in range(11):
        write_obj(tmp_path / f"f{k}.obj", P[k], F)  # f10 must come after f9, not after f1
    c = read_mesh_sequence(tmp_path, rate=25)
    np.testing.assert_allclose(c.frames[10], P[10].ravel(), atol=1e-6)


def test_sequence_consistency_errors(tmp_path):
    P, F = _frames(n=5)
    d = tmp_path / "s"
    write_mesh_sequence(d, P, faces=F)
    with pytest.raises(ImportFormatError, match="carry no timing; give the frame rate"):
        read_mesh_sequence(d)
    write_obj(d / "frame_00003.obj", P[3][:-1], None)
    with pytest.raises(ImportFormatError, match="frame_00003.obj, frame 3: has 11 vertices.*has 12") as e:
        read_mesh_sequence(d, rate=30)
    assert e.value.frame == 3
    write_obj(d / "frame_00003.obj", P[3], F[::-1])
    with pytest.raises(ImportFormatError, match="faces differ"):
        read_mesh_sequence(d, rate=30)
    with pytest.raises(ImportFormatError, match="one mesh file, i.e. one frame"):
        read_corpus(d / "frame_00000.obj", rate=30)


def test_stale_frames_are_refused_or_cleared(tmp_path):
    P, F = _frames(n=6)
    d = tmp_path / "s"
    write_mesh_sequence(d, P, faces=F)
    before = {p: p.read_bytes() for p in d.iterdir()}
    with pytest.raises(ValueError, match=r"already holds 3 other 'frame_\*\.obj'"):
        write_mesh_sequence(d, P[:3] + 1, faces=F)
    assert {p: p.read_bytes() for p in d.iterdir()} == before  # refused before writing anything
    files = write_mesh_sequence(d, P[:3] + 1, faces=F, clear=True)
    assert sorted(d.iterdir()) == files
    np.testing.assert_allclose(read_mesh_sequence(d, rate=30).frames, (P[:3] + 1).reshape(3, -1), atol=1e-6)


def test_vertex_array_with_template(tmp_path):
    P, F = _frames(n=8)
    npy = tmp_path / "seq.npy"
    np.save(npy, P)
    tpl = write_ply(tmp_path / "template.ply", P[0], F)
    c = read_vertex_array(npy, template=tpl, rate=60)
    assert c.rate == 60 and c.n_frames == 8 and c.faces.shape == F.shape
    np.testing.assert_array_equal(c.frames, P.reshape(8, -1))
    np.save(tmp_path / "flat.npy", P.reshape(8, -1).astype(np.float64))
    assert read_corpus(tmp_path / "flat.npy", rate=60).n_points == 12
    with pytest.raises(ImportFormatError, match="template has 11 vertices; seq.npy has 12"):
        read_vertex_array(npy, template=write_obj(tmp_path / "t.obj", P[0][:-1]), rate=60)
    np.save(tmp_path / "bad.npy", np.zeros((4, 5)))
    with pytest.raises(ImportFormatError, match=r"shape \(4, 5\); expected \(n_frames, V, 3\)"):
        read_vertex_array(tmp_path / "bad.npy", rate=60)
    with pytest.raises(ImportFormatError, match="give the frame rate"):
        read_vertex_array(npy)


def _polygon_ply(path, V, polys, *, fmt, count="uchar", index="int", extra=True):
    """A PLY with faces of varying length, written row by row (the reference layout)."""
    e = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fmt)
    head = (f"ply\nformat {fmt} 1.0\nelement vertex {len(V)}\nproperty float x\nproperty float y\n"
            f"property float z\nelement face {len(polys)}\n" + ("property uchar flag\n" if extra else "")
            + f"property list {count} {index} vertex_indices\n" + ("property float quality\n" if extra else "")
            + "end_header\n").encode()
    types = {"uchar": "u1", "ushort": "u2", "uint": "u4", "int": "i4"}
    if e is None:
        body = "".join(f"{x} {y} {z}\n" for x, y, z in V.tolist())
        body += "".join(("7 " if extra else "") + " ".join(map(str, [len(q), *q])) + (" 0.5" if extra else "") + "\n"
                        for q in polys)
        path.write_bytes(head + body.encode())
        return path
    out = bytearray(V.astype(e + "f4").tobytes())
    for q in polys:
        if extra:
            out += b"\x07"
        out += np.array([len(q)], e + types[count]).tobytes() + np.array(q, e + types[index]).tobytes()
        if extra:
            out += np.array([0.5], e + "f4").tobytes()
    path.write_bytes(head + bytes(out))
    return path


@pytest.mark.parametrize("fmt, count, index, extra", [
    ("binary_little_endian", "uchar", "int", False), ("binary_little_endian", "ushort", "uint", True),
    ("binary_big_endian", "uint", "int", True), ("ascii", "uchar", "int", False), ("ascii", "uchar", "int", True),
])
def test_ply_faces_of_varying_length_read_without_a_row_loop(tmp_path, monkeypatch, fmt, count, index, extra):
    """Triangles, quads and pentagons mixed: the vectorised readers give the fans a per-row reader gives,
    also when the binary row finder works through several windows."""
    import engine.io.readers.meshfile as mf

    monkeypatch.setattr(mf, "_CHUNK", 97)  # many windows, rows straddling their edges
    rng = np.random.default_rng(5)
    V = rng.normal(size=(40, 3)).astype(np.float32)
    polys = [rng.integers(0, 40, size=k).tolist() for k in rng.choice([3, 4, 5], size=300)]
    V2, F2 = read_ply(_polygon_ply(tmp_path / "p.ply", V, polys, fmt=fmt, count=count, index=index, extra=extra))
    expected = [(q[0], q[j], q[j + 1]) for q in polys for j in range(1, len(q) - 1)]
    np.testing.assert_array_equal(V2, V)
    assert F2.tolist() == [list(t) for t in expected]


@pytest.mark.parametrize("fmt", ["binary_little_endian", "ascii"])
def test_ply_short_and_truncated_faces_are_named(tmp_path, fmt):
    V = np.eye(3)
    p = _polygon_ply(tmp_path / "s.ply", V, [[0, 1, 2]] + [[]] * 1000 + [[0, 1]], fmt=fmt, extra=False)
    with pytest.raises(ImportFormatError, match=r"face 1 has 0 vertices; expected at least 3 \(1001 faces"):
        read_ply(p)
    p = _polygon_ply(tmp_path / "t.ply", V, [[0, 1, 2], [0, 1, 2, 1]] * 50, fmt=fmt, extra=False)
    data = p.read_bytes()
    p.write_bytes(data[:-7])
    with pytest.raises(ImportFormatError, match="truncated|row 99"):
        read_ply(p)
