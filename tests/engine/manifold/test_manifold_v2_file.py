"""Manifold files written before the fitted attributes were declared on the estimators still load.

``data/manifold_v2.npz`` was written by ``data/make_manifold_v2.py`` at commit 73b387e, when
the file's schema was a table in ``engine.manifold.model``; it is now read from each
estimator's ``_persisted_attributes``.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from engine.files.persist import read_npz
from engine.manifold.model import Manifold, ManifoldFileError

OLD = Path(__file__).with_name("data") / "manifold_v2.npz"


def _json(key) -> bool:
    return key.endswith(("__kinds__", "__params__")) or key in ("manifold_params", "manifold_timings")


@pytest.fixture(scope="module")
def old():
    return Manifold.load(OLD)


def test_an_older_file_loads_with_every_declared_attribute(old):
    s = old.summary()
    assert (s["corpus"], s["frames"], s["points"], s["utterances"]) == ("small-8", 473, 8, 2)
    for attr in Manifold._PARTS.values():
        part = getattr(old, attr)
        held = {**vars(part), **vars(part).get("_csr_parts", {})}  # a csr one may wait for its first use
        missing = [a for a in type(part)._persisted_attributes if a not in held]
        assert not missing, f"{attr}: {missing}"
    assert old.state_x_ is not None and old.state_x_.shape == (s["n_states"], s["shape_components"])
    # it works as a manifold: the training frames project onto their own F^y
    u = old.corpus_.utterances[0]
    Y = old.project(old.corpus_.frames[u.start:u.stop])
    assert np.abs(Y - old.Fy_[u.start:u.stop]).max() < 1e-3 * np.abs(old.Fy_).max()


def test_an_older_file_saved_again_holds_the_same_arrays(old, tmp_path):
    before, after = read_npz(OLD), read_npz(old.save(tmp_path / "again.npz"))
    assert sorted(after) == sorted(before)
    for key, a in before.items():
        if _json(key):  # the same JSON (a loaded part lists its attributes in another order)
            assert json.loads(str(after[key])) == json.loads(str(a)), key
        else:
            assert after[key].dtype == a.dtype, key
            np.testing.assert_array_equal(after[key], a, err_msg=key)


def test_a_new_fit_writes_the_fields_an_older_file_has(old, tmp_path):
    """The same corpus fitted by the current code: the same fields, kinds, dtypes and parameters."""
    before = read_npz(OLD)
    after = read_npz(Manifold().fit(old.corpus_).save(tmp_path / "new.npz"))
    assert sorted(after) == sorted(before)
    for key, a in before.items():
        b = after[key]
        assert (b.dtype.kind, b.ndim) == (a.dtype.kind, a.ndim), key
        assert b.dtype == a.dtype or a.dtype.kind == "U", key
        if key.endswith("__class__"):
            assert str(b) == str(a), key
        elif _json(key) and key != "manifold_timings":
            assert json.loads(str(b)) == json.loads(str(a)), key
    np.testing.assert_allclose(after["Fy"], before["Fy"], atol=1e-3 * np.abs(before["Fy"]).max())


def test_a_declared_attribute_missing_from_a_file_is_named(tmp_path):
    d = read_npz(OLD)
    kinds = json.loads(str(d["tangent/__kinds__"]))
    del kinds["classes_"]
    d["tangent/__kinds__"] = np.array(json.dumps(kinds))
    bad = tmp_path / "bad.npz"
    with open(bad, "wb") as fh:
        np.savez(fh, **d)
    with pytest.raises(ManifoldFileError, match=r"bad.npz: field 'tangent/__kinds__': .*\['classes_'\] missing"):
        Manifold.load(bad)


def test_a_saved_parameter_outside_its_constraints_is_refused(tmp_path):
    d = read_npz(OLD)
    params = json.loads(str(d["embedding/__params__"]))
    params["method"] = "tsne"
    d["embedding/__params__"] = np.array(json.dumps(params))
    bad = tmp_path / "bad.npz"
    with open(bad, "wb") as fh:
        np.savez(fh, **d)
    with pytest.raises(ManifoldFileError, match=r"field 'embedding/__params__.method': method must be one of "
                                                r"'pca', 'mds', got 'tsne'$"):
        Manifold.load(bad)
