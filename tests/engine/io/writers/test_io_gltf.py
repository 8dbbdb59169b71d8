"""glTF morph-target export: read back with pygltflib, base + weights x targets reproduces the frames."""
import numpy as np
import pygltflib
import pytest

from engine.io.writers.gltf import read_gltf_morph, write_gltf_morph

_DTYPES = {5126: np.float32, 5123: np.uint16, 5125: np.uint32}
_WIDTH = {"SCALAR": 1, "VEC3": 3}


def _load(path):
    """The glTF document and a reader of its accessors, decoded with pygltflib only."""
    gltf = pygltflib.GLTF2().load(str(path))
    buf = gltf.buffers[0]
    blob = gltf.binary_blob() if buf.uri is None else gltf.get_data_from_buffer_uri(buf.uri)

    def accessor(i):
        a = gltf.accessors[i]
        v = gltf.bufferViews[a.bufferView]
        w = _WIDTH[a.type]
        arr = np.frombuffer(blob, _DTYPES[a.componentType], count=a.count * w, offset=v.byteOffset + a.byteOffset)
        return arr.reshape(a.count, w)

    return gltf, accessor


def _position(attributes):
    """POSITION accessor index (pygltflib loads morph targets as plain dicts)."""
    return attributes["POSITION"] if isinstance(attributes, dict) else attributes.POSITION


def _played_frames(gltf, accessor):
    """What a viewer shows at each key: base + sum_k w_k(t) target_k, as (n, V, 3) plus key times."""
    prim = gltf.meshes[0].primitives[0]
    base = accessor(prim.attributes.POSITION)
    targets = np.stack([accessor(_position(t)) for t in prim.targets])
    anim = gltf.animations[0]
    ch = anim.channels[0]
    assert ch.target.path == "weights" and ch.target.node == 0 and gltf.nodes[0].mesh == 0
    sampler = anim.samplers[ch.sampler]
    times = accessor(sampler.input).ravel()
    w = accessor(sampler.output).reshape(len(times), len(targets))
    return base[None] + np.einsum("nk,kvd->nvd", w, targets), times, sampler.interpolation


@pytest.fixture(scope="module")
def synthesized(small_manifold):
    from engine.phonetics.targets import targets_from_phones
    from engine.synthesis.methods import make_synthesizer

    targets = targets_from_phones(small_manifold, "sil 0.1 b 0.08 aa 0.12 m 0.08 sil 0.1")
    return make_synthesizer("viterbi", small_manifold, strict=False).synthesize(targets)


def test_glb_reproduces_synthesised_frames_within_float32(small_manifold, synthesized, tmp_path):
    m, traj = small_manifold, synthesized
    c, shape = m.corpus_, m.shape_
    p = write_gltf_morph(tmp_path / "speech.glb", shape.mean_, shape.components_, traj.Fx, rate=c.rate,
                         faces=c.faces, dims=c.dims, scale=0.001, audio="speech.wav")
    gltf, accessor = _load(p)
    played, times, interp = _played_frames(gltf, accessor)
    frames = traj.frames(m).reshape(traj.n_frames, -1, 3)
    assert played.shape == frames.shape and interp == "LINEAR"
    # float32 data, float32 sums in another order: a few ulps of the coordinate scale
    tol = 8 * np.finfo(np.float32).eps * float(np.abs(frames).max()) * np.sqrt(shape.n_components_)
    np.testing.assert_allclose(played, frames, rtol=0, atol=tol)
    np.testing.assert_allclose(times, np.arange(traj.n_frames) / c.rate, rtol=1e-6)
    # weights within [0, 1] (F^x runs to tens of mm and changes sign; Blender's sliders stop at
    # +-10 and its 3.4 importer clamps at 0): X_k+ and X_k- targets; F^x comes back exactly
    r = read_gltf_morph(p)
    m = shape.n_components_
    assert r["weights"].min() == 0.0 and r["weights"].max() == pytest.approx(1.0) and np.abs(traj.Fx).max() > 10
    assert r["weights"].shape == (traj.n_frames, 2 * m)
    np.testing.assert_allclose(r["Fx"], traj.Fx, rtol=1e-6, atol=1e-6 * float(np.abs(traj.Fx).max()))
    np.testing.assert_allclose(r["target_scale"][::2], np.abs(traj.Fx).max(axis=0), rtol=1e-6)
    np.testing.assert_array_equal(r["target_scale"][1::2], -r["target_scale"][::2])
    prim = gltf.meshes[0].primitives[0]
    assert prim.mode == pygltflib.TRIANGLES
    np.testing.assert_array_equal(accessor(prim.indices).reshape(-1, 3), c.faces)
    assert gltf.meshes[0].extras["targetNames"] == [f"X{k + 1}{sign}" for k in range(m) for sign in "+-"]
    assert gltf.meshes[0].weights == [0.0] * (2 * m)
    assert gltf.nodes[0].scale == [0.001] * 3
    assert gltf.scenes[0].extras["audio"] == "speech.wav" and gltf.scenes[0].extras["rate"] == c.rate
    # POSITION accessors (base and targets) carry the min/max the standard requires
    for t in [prim.attributes] + list(prim.targets):
        a = gltf.accessors[_position(t)]
        np.testing.assert_allclose(a.min, accessor(_position(t)).min(0), rtol=1e-6)
        np.testing.assert_allclose(a.max, accessor(_position(t)).max(0), rtol=1e-6)


def test_points_without_faces_2d_step_and_embedded_gltf(tmp_path):
    rng = np.random.default_rng(0)
    V, m, n = 5, 3, 9
    mean = rng.normal(size=2 * V)
    comps = rng.normal(size=(m, 2 * V))
    W = rng.normal(size=(n, m))
    p = write_gltf_morph(tmp_path / "markers.gltf", mean, comps, W, rate=100.0, dims=2, interpolation="STEP",
                         target_names=["open", "round", "spread"], two_sided=False)
    assert p.read_text(encoding="utf-8").lstrip().startswith("{")  # JSON with the buffer inside
    gltf, accessor = _load(p)
    played, times, interp = _played_frames(gltf, accessor)
    prim = gltf.meshes[0].primitives[0]
    assert prim.mode == pygltflib.POINTS and prim.indices is None and interp == "STEP"
    expect = (mean + W @ comps).reshape(n, V, 2)
    np.testing.assert_allclose(played[..., :2], expect, atol=1e-5)
    np.testing.assert_array_equal(played[..., 2], 0.0)
    np.testing.assert_allclose(times, np.arange(n) / 100.0, rtol=1e-6)
    assert gltf.meshes[0].extras["targetNames"] == ["open", "round", "spread"]
    # the module's own reader agrees with the decoding above
    r = read_gltf_morph(p)
    np.testing.assert_array_equal(r["base"][None] + np.einsum("nk,kvd->nvd", r["weights"], r["targets"]), played)
    assert r["faces"] is None and r["interpolation"] == "STEP" and r["target_names"] == ["open", "round", "spread"]
    assert r["extras"] == {"rate": 100.0, "frames": n} and r["scale"] == 1.0
    assert np.abs(r["weights"]).max() == pytest.approx(1.0) and r["weights"].min() < 0  # one signed target each
    np.testing.assert_allclose(r["Fx"], W, rtol=1e-6, atol=1e-6)
    (tmp_path / "broken.glb").write_bytes(p.read_bytes()[:40])
    with pytest.raises(ValueError, match="broken.glb: not a readable glTF"):
        read_gltf_morph(tmp_path / "broken.glb")


def test_bad_input_names_the_problem_and_leaves_the_old_file(tmp_path):
    mean, comps, W = np.zeros(6), np.ones((2, 6)), np.zeros((4, 2))
    out = tmp_path / "a.glb"
    out.write_bytes(b"old")
    with pytest.raises(ValueError, match=r"must end in \.glb"):
        write_gltf_morph(tmp_path / "a.obj", mean, comps, W, rate=60)
    with pytest.raises(ValueError, match=r"shape \(n_frames, 2\) for 2 components, got \(4, 3\)"):
        write_gltf_morph(out, mean, comps, np.zeros((4, 3)), rate=60)
    bad = W.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="row 2 holds NaN"):
        write_gltf_morph(out, mean, comps, bad, rate=60)
    with pytest.raises(ValueError, match="rate=0"):
        write_gltf_morph(out, mean, comps, W, rate=0)
    with pytest.raises(ValueError, match=r"indices into 2 points"):
        write_gltf_morph(out, mean, comps, W, rate=60, faces=[[0, 1, 2]])
    with pytest.raises(ValueError, match="interpolation="):
        write_gltf_morph(out, mean, comps, W, rate=60, interpolation="CUBICSPLINE")
    assert out.read_bytes() == b"old" and sorted(q.name for q in tmp_path.iterdir()) == ["a.glb"]
