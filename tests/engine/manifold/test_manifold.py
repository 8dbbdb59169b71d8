import numpy as np
import pytest
import scipy.sparse as sp

from engine.manifold.model import Manifold, ManifoldFileError
from engine.progress import Cancelled


def _assert_same_estimator(a, b):
    assert a.get_params() == b.get_params()
    names = [k for k in vars(a) if k.endswith("_") and not k.startswith("_")]
    assert names, type(a)
    for k in names:
        x, y = getattr(a, k), getattr(b, k)
        if sp.issparse(x):
            assert (x != y).nnz == 0, k
        elif isinstance(x, np.ndarray):
            np.testing.assert_array_equal(x, y, err_msg=k)
        else:
            assert x == y, k


def test_save_load_round_trips_exactly(small_manifold, tmp_path):
    path = small_manifold.save(tmp_path / "m.npz")
    m = Manifold.load(path)
    for attr in ("Fx_", "Fxv_", "G_", "Fy_"):
        np.testing.assert_array_equal(getattr(m, attr), getattr(small_manifold, attr))
    for part in ("shape_", "dynamics_", "embedding_", "tangent_", "states_"):
        _assert_same_estimator(getattr(small_manifold, part), getattr(m, part))
    np.testing.assert_array_equal(m.corpus_.frames, small_manifold.corpus_.frames)
    assert m.corpus_.utterances == small_manifold.corpus_.utterances
    assert m.get_params() == small_manifold.get_params()
    # the loaded object works without refitting
    np.testing.assert_allclose(m.embedding_.transform(m.G_[:20]), m.Fy_[:20], atol=1e-3 * np.abs(m.Fy_).max())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.npz"]


def test_memory_mapped_load_reads_the_same_arrays_from_the_file(small_manifold, tmp_path):
    """memory_map=True leaves every stored array on disk (read-only maps), equal to the fitted ones."""
    from engine.files.mapped import release_pages

    path = small_manifold.save(tmp_path / "m.npz")
    m = Manifold.load(path, memory_map=True)
    for attr in ("Fx_", "Fxv_", "G_", "Fy_"):
        a = getattr(m, attr)
        assert isinstance(a, np.memmap) and not a.flags.writeable
        np.testing.assert_array_equal(a, getattr(small_manifold, attr))
    assert isinstance(m.tangent_.s_, np.memmap) and isinstance(m.states_.labels_, np.memmap)
    np.testing.assert_array_equal(m.states_.labels_, small_manifold.states_.labels_)
    np.testing.assert_array_equal(m.corpus_.frames, small_manifold.corpus_.frames)
    release_pages(m.Fy_[10:500])  # the pages go back to the file cache; the values stay readable
    release_pages(np.ones(3))  # an array in memory: nothing to do
    np.testing.assert_array_equal(m.Fy_[10:500], small_manifold.Fy_[10:500])
    assert not isinstance(Manifold.load(path, memory_map=False).Fy_, np.memmap)


def test_save_without_frames_reconstructs(small_manifold, tmp_path):
    path = small_manifold.save(tmp_path / "m.npz", include_frames=False)
    m = Manifold.load(path)
    expected = small_manifold.shape_.inverse_transform(small_manifold.Fx_)
    np.testing.assert_allclose(m.corpus_.frames, expected, rtol=0, atol=1e-5)


def test_project_training_frames_reproduces_fy(small_manifold):
    c = small_manifold.corpus_
    u = c.utterances[1]
    Y = small_manifold.project(c.frames[u.start:u.stop])
    ref = small_manifold.Fy_[u.start:u.stop]
    assert np.abs(Y - ref).max() / np.abs(small_manifold.Fy_).max() < 1e-3


def test_load_errors_name_the_file(tmp_path, small_corpus):
    with pytest.raises(ManifoldFileError, match="no such"):
        Manifold.load(tmp_path / "missing.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(ManifoldFileError, match="junk.npz"):
        Manifold.load(tmp_path / "junk.npz")
    small_corpus.save(tmp_path / "corpus.npz")
    with pytest.raises(ManifoldFileError, match="corpus file"):
        Manifold.load(tmp_path / "corpus.npz")


def test_fit_can_be_cancelled(small_corpus):
    calls = []

    def progress(stage, done, total):
        calls.append(stage)
        if stage == "embedding":
            raise Cancelled()

    m = Manifold()
    with pytest.raises(Cancelled):
        m.fit(small_corpus, progress=progress)
    assert "shape space" in calls and not hasattr(m, "Fy_")


@pytest.mark.parametrize("content", [b"", b"PK\x03\x04 truncated zip", bytes(range(256)) * 4],
                         ids=["empty", "truncated-zip", "random-bytes"])
def test_damaged_files_give_the_documented_errors(tmp_path, small_manifold, content):
    from app.cli import main
    from engine.recordings.corpus import Corpus, CorpusError

    bad = tmp_path / "damaged.npz"
    bad.write_bytes(content)
    with pytest.raises(ManifoldFileError, match=r"damaged.npz: not a readable .npz manifold file"):
        Manifold.load(bad)
    with pytest.raises(CorpusError, match="damaged.npz: cannot read as a Lipspace corpus"):
        Corpus.load(bad)
    # a half-written manifold (the first bytes of a real one) is refused the same way
    good = small_manifold.save(tmp_path / "good.npz")
    half = tmp_path / "half.npz"
    half.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    with pytest.raises(ManifoldFileError, match="half.npz"):
        Manifold.load(half)
    assert main(["info", str(bad)]) == 2


# ---------------------------------------------------------------- validated loader (issue 16)
@pytest.fixture(scope="module")
def saved_arrays(small_manifold, tmp_path_factory):
    from engine.files.persist import read_npz

    path = small_manifold.save(tmp_path_factory.mktemp("m") / "m.npz")
    return read_npz(path)


def _set(key, fn):
    return lambda d: d.__setitem__(key, fn(d[key]))


def _json(key, text):
    return lambda d: d.__setitem__(key, np.array(text))


# each case: how the file is damaged, and the field the error must name
DAMAGE = {
    "csr-indices-out-of-range": (_set("states/adjacency_.indices", lambda a: a + 10**6), "adjacency_.indices"),
    "csr-indptr-decreasing": (_set("states/transition_.indptr", lambda a: a[::-1].copy()), "transition_.indptr"),
    "csr-shape-not-K": (_set("states/counts_.shape", lambda a: a + 1), "counts_.shape"),
    "labels-not-below-K": (_set("states/labels_", lambda a: a + 1000), "states/labels_"),
    "centroids-fewer-than-labels": (_set("states/centroids_", lambda a: a[:-3]), "states/labels_"),
    "components-wrong-width": (_set("shape/components_", lambda a: a[:, :-1]), "shape/components_"),
    "embedding-components-vs-Fy": (_set("embedding/components_", lambda a: a[:-1]), "embedding/components_"),
    "nan-in-Fy": (_set("Fy", lambda a: np.where(np.arange(a.size).reshape(a.shape) == 7, np.nan, a)), "Fy"),
    "Fx-float-as-str": (_set("Fx", lambda a: a.astype(str)), "Fx"),
    "params-bad-json": (_json("manifold_params", "{bad"), "manifold_params"),
    "params-a-list": (_json("manifold_params", "[1, 2]"), "manifold_params"),
    "params-unknown-key": (_json("manifold_params", '{"foo": 1}'), "manifold_params"),
    "params-wrong-type": (_json("manifold_params", '{"n_states": "x"}'), "manifold_params.n_states"),
    "params-vs-arrays": (_json("manifold_params", '{"n_embedding": 3}'), "n_embedding"),
    "estimator-params-unknown": (_json("embedding/__params__", '{"zzz": 3}'), "embedding/__params__"),
    "kinds-unknown": (_json("states/__kinds__", '{"labels_": "pickle"}'), "states/__kinds__"),
    "timings-bad-json": (_json("manifold_timings", "{{"), "manifold_timings"),
    "timings-a-list": (_json("manifold_timings", "[]"), "manifold_timings"),
    "version-not-int": (_json("manifold_version", "one"), "manifold_version"),
    "version-float": (lambda d: d.__setitem__("manifold_version", np.array(1.5)), "manifold_version"),
    "scc-label-out-of-range": (_set("states/scc_labels_", lambda a: a + 99), "scc_labels_"),
    "phone-utterance-out-of-range": (_set("corpus_phone_utt", lambda a: a + 10**4), "corpus_phone_utt"),
    "bounds-1d": (_set("corpus_utt_bounds", lambda a: a[:, 0].copy()), "corpus_utt_bounds"),
    "frames-missing-Fx-short": (lambda d: (d.pop("corpus_frames"), d.__setitem__("Fx", d["Fx"][:-5])), "Fxv"),
}


@pytest.mark.parametrize("memory_map", [None, True])
@pytest.mark.parametrize("case", sorted(DAMAGE))
def test_damaged_manifold_is_refused_naming_the_field(saved_arrays, tmp_path, case, memory_map):
    damage, field = DAMAGE[case]
    d = {k: v.copy() for k, v in saved_arrays.items()}
    damage(d)
    path = tmp_path / "bad.npz"
    with open(path, "wb") as fh:
        np.savez(fh, **d)
    with pytest.raises(ManifoldFileError) as err:
        Manifold.load(path, memory_map=memory_map)  # True: every array checked as a map of the file
    msg = str(err.value)
    assert msg.startswith(str(path)) and field in msg and "\n" not in msg, msg


def test_out_of_range_csr_gives_exit_2_not_a_segfault(saved_arrays, tmp_path):
    """It used to crash `lipspace info` with SIGSEGV inside scipy's dijkstra."""
    import subprocess
    import sys

    d = dict(saved_arrays)
    d["states/adjacency_.indices"] = d["states/adjacency_.indices"] + 10**6
    path = tmp_path / "bad.npz"
    with open(path, "wb") as fh:
        np.savez(fh, **d)
    r = subprocess.run([sys.executable, "-m", "app.cli", "info", str(path)], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2, r.stderr[-2000:]
    assert r.stderr.startswith("lipspace info: error:") and "adjacency_.indices" in r.stderr
    assert "Traceback" not in r.stderr


def test_zip_bomb_is_refused_before_inflating(tmp_path):
    import zipfile

    path = tmp_path / "bomb.npz"
    header = np.lib.format
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        with zf.open("manifold_version.npy", "w", force_zip64=True) as f:
            header.write_array_header_1_0(f, {"descr": "<f8", "fortran_order": False, "shape": (2**25,)})
            chunk = bytes(2**20)
            for _ in range(2**28 // 2**20):  # 256 MiB of zeros in a ~0.3 MiB file
                f.write(chunk)
    assert path.stat().st_size < 4 * 2**20
    with pytest.raises(ManifoldFileError, match="decompression bomb"):
        Manifold.load(path)


def test_array_header_larger_than_its_member_is_refused(tmp_path):
    import zipfile

    path = tmp_path / "liar.npz"
    with zipfile.ZipFile(path, "w") as zf:
        with zf.open("Fx.npy", "w") as f:
            np.lib.format.write_array_header_1_0(f, {"descr": "<f8", "fortran_order": False,
                                                     "shape": (10**6, 10**6)})
    with pytest.raises(ManifoldFileError, match="declares shape"):
        Manifold.load(path)


def test_fifo_is_refused_without_blocking(tmp_path):
    import os

    fifo = tmp_path / "pipe.npz"
    os.mkfifo(fifo)
    with pytest.raises(ManifoldFileError, match="not a regular file"):
        Manifold.load(fifo)


@pytest.mark.parametrize("value", [["x.npz"], 3, "/etc/passwd", "../../../../etc/passwd", "dir.npz", "pipe.npz",
                                   "absent.npz"])
def test_session_source_must_be_a_regular_data_file(tmp_path, value):
    import json
    import os

    from app.files.session import SessionError, load_session

    (tmp_path / "dir.npz").mkdir()
    os.mkfifo(tmp_path / "pipe.npz")
    s = tmp_path / "s.json"
    s.write_text(json.dumps({"lipspace_session": 1, "source": {"path": value}}))
    with pytest.raises(SessionError, match="source.path") as err:
        load_session(s)
    assert "root:" not in str(err.value)  # nothing of the named file is shown


def test_session_source_accepts_a_data_file(tmp_path, small_corpus):
    import json

    from app.files.session import load_session

    small_corpus.save(tmp_path / "c.npz")
    s = tmp_path / "s.json"
    s.write_text(json.dumps({"lipspace_session": 1, "source": {"path": "c.npz"}}))
    assert load_session(s)["source"]["path"] == str((tmp_path / "c.npz").resolve())


def test_cache_keys_follow_code_and_parameters(tmp_path, monkeypatch):
    import engine.files.persist as persist
    from engine.manifold.model import algorithm_fingerprint, fit_modules
    from engine.talker.synthetic import generator_fingerprint

    base = algorithm_fingerprint()
    assert algorithm_fingerprint() == base and len(base) == 16
    assert algorithm_fingerprint({**Manifold().get_params(), "n_states": 50}) != base
    gen = generator_fingerprint()
    # an edit to a fitting module changes the key (simulated: the module's source read differently)
    real_open = open

    def edited(path, mode="r", *a, **kw):
        fh = real_open(path, mode, *a, **kw)
        if str(path).endswith("embedding.py") and "b" in mode:
            data = fh.read() + b"\n# edited\n"
            fh.close()
            import io

            return io.BytesIO(data)
        return fh

    monkeypatch.setattr("builtins.open", edited)
    assert "engine.manifold.embedding" in fit_modules()
    assert algorithm_fingerprint() != base
    assert generator_fingerprint() == gen
    assert persist.source_fingerprint(("engine.manifold.embedding",)) != ""


def test_cache_key_covers_every_engine_module_a_fit_imports(tmp_path):
    """The key's modules are read from the imports; a fit that imports an engine module they do not
    list (a new module, or one imported by name at run time) fails here."""
    import subprocess
    import sys

    from engine.manifold.model import fit_modules

    code = ("import sys, warnings\n"
            "from engine.talker.synthetic import load_synthetic\n"
            "from engine.manifold.model import Manifold\n"
            "c = load_synthetic(preset='small')\n"
            "c = c.subset([u.id for u in c.utterances[:8]])\n"
            "before = set(sys.modules)\n"
            "with warnings.catch_warnings():\n"
            "    warnings.simplefilter('ignore')\n"
            f"    Manifold(n_states=20).fit(c).save({str(tmp_path / 'm.npz')!r})\n"
            "print(' '.join(sorted(m for m in sys.modules if m.startswith('engine') and m not in before)))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    used = set(r.stdout.split())
    covered = set(fit_modules())
    assert used, "the fit imported no engine module after the corpus was made: the check sees nothing"
    missing = used - covered - {"engine"}
    assert not missing, f"modules the fit imports but the cache key leaves out: {sorted(missing)}"
    assert {"engine.recordings.registration", "engine.recordings.kinematics", "engine.manifold.buildplan",
            "engine.manifold.inverse", "engine.manifold.tangent", "engine.manifold.local_gradients"} <= covered


def test_the_cache_key_finds_every_engine_import_the_parser_finds():
    """fit_modules reads imports with a pattern (fast at every start): on every engine module it finds the engine
    imports Python's own parser finds."""
    import ast
    from pathlib import Path

    from engine.manifold.model import _engine_imports

    root = Path(__file__).resolve().parents[3] / "engine"
    for f in root.rglob("*.py"):
        text = f.read_text(encoding="utf-8")
        want = set()
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.Import):
                want |= {a.name for a in node.names if a.name.split(".")[0] == "engine"}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").split(".")[0] == "engine":
                want |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
        assert want <= set(_engine_imports(text)), f"{f}: {sorted(want - set(_engine_imports(text)))}"


def test_deeply_nested_session_is_a_session_error(tmp_path):
    from app.files.session import SessionError, load_session

    s = tmp_path / "deep.json"
    s.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(SessionError, match="nested too deeply"):
        load_session(s)


def test_importers_refuse_a_fifo(tmp_path):
    import os

    from engine.io import ImportFormatError, read_corpus

    fifo = tmp_path / "pipe.ema"
    os.mkfifo(fifo)
    with pytest.raises(ImportFormatError, match="not a regular file"):
        read_corpus(fifo)


@pytest.mark.parametrize("bad", [{"selection": {"frame": 10**9}}, {"component": "x"}, {"visible_phones": 5},
                                 {"hemisphere": ["future"]}, {"utterance": 3}])
def test_session_values_of_the_wrong_type_or_range_are_session_errors(small_manifold, bad):
    from app.files.session import SessionError, apply_session
    from app.models.state import AppState

    with pytest.raises(SessionError, match="does not fit"):
        apply_session(AppState(small_manifold), {"_file": "s.json", **bad})


def test_atomic_write_removes_parts_left_by_a_killed_process(tmp_path):
    import os
    import time

    from engine.files.atomic import STALE_PART_SECONDS, write_text_atomic

    stale = tmp_path / ".m.abc123.part.npz"
    fresh = tmp_path / ".m.def456.part.npz"  # another process writing right now
    other = tmp_path / ".n.abc123.part.npz"  # a temporary file of another target
    for p in (stale, fresh, other):
        p.write_bytes(b"x" * 100)
    old = time.time() - STALE_PART_SECONDS - 60
    os.utime(stale, (old, old))
    os.utime(other, (old, old))
    write_text_atomic(tmp_path / "m.npz", "content")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([fresh.name, other.name, "m.npz"])


def test_dynamics_scale_reaches_the_dynamic_features_and_round_trips(small_corpus, small_manifold, tmp_path):
    """Manifold(dynamics_scale="p99") scales G's blocks by a percentile, not the maximum."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the p99 scale may warn that the maximum is far above it
        m = Manifold(dynamics_scale="p99").fit(small_corpus)
    assert m.dynamics_.scale == "p99" and small_manifold.dynamics_.scale == "max"
    assert not np.allclose(m.dynamics_.alpha_, small_manifold.dynamics_.alpha_)
    m2 = Manifold.load(m.save(tmp_path / "p99.npz"))
    assert m2.dynamics_scale == "p99"
    np.testing.assert_array_equal(m2.Fy_, m.Fy_)


def test_state_inverse_table_of_the_landmark_path_comes_from_local_triangulations(small_corpus, small_manifold):
    """The landmark (large-corpus) build does not tetrahedralise all frames: the map at the state points
    comes from triangulations of their neighbourhoods, the same values as the whole map's; a file
    without the table gets it on first synthesis, the same way."""
    from engine.manifold.inverse import InverseMap, delaunay_at
    from engine.phonetics.targets import targets_from_utterance
    from engine.synthesis.viterbi import ViterbiSynthesizer

    assert small_manifold.state_x_ is not None
    m = Manifold(n_landmarks=300).fit(small_corpus)
    assert m.state_x_ is not None and m._inverse is None  # no tetrahedralisation of every frame
    C = np.asarray(m.states_.centroids_, np.float64)
    whole = InverseMap(n_dims=3).fit(m.Fy_, m.Fx_)
    np.testing.assert_allclose(m.state_x_, whole.transform(C), rtol=0, atol=1e-5 * np.abs(m.Fx_).max())
    rng = np.random.default_rng(0)  # any point inside the frames' hull, not only centroids
    q = m.Fy_[rng.choice(len(m.Fy_), 40), :3] * 0.6 + m.Fy_[rng.choice(len(m.Fy_), 40), :3] * 0.4
    got = delaunay_at(m.Fy_, m.Fx_, q)
    ok = ~np.isnan(got).any(axis=1)
    assert ok.mean() > 0.9
    np.testing.assert_allclose(got[ok], whole.transform(q)[ok], rtol=0, atol=1e-5 * np.abs(m.Fx_).max())
    m.state_x_ = None  # as a file of an older build
    u = m.corpus_.utterances[0]
    traj = ViterbiSynthesizer(strict=False).fit(m).synthesize(targets_from_utterance(m, u.id, on_collision="merge"))
    assert np.isfinite(traj.Fx).all() and m.state_x_ is not None and m._inverse is None
