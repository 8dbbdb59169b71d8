"""``lipspace import`` over many files: one backend maps the readers over them; an unreadable one stops the
import, or with --skip-bad is skipped with the reason (issue 13 item 3, issue 30 item 3)."""
import numpy as np
import pytest

from app.cli import main
from engine.io import write_est_track
from engine.recordings.corpus import Corpus


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Six short EMA recordings (EST tracks at 250 Hz, two lip sensors) and one file that is not EMA."""
    d = tmp_path_factory.mktemp("many")
    rng = np.random.default_rng(3)
    paths = []
    for i in range(6):
        n = 60 + 10 * i
        t = np.arange(n) / 250.0
        v = np.cumsum(rng.normal(size=(n, 4)), axis=0)
        paths.append(str(write_est_track(d / f"spk{i % 2}_{i:02d}.ema", t, v, ["ul_x", "ul_y", "ll_x", "ll_y"])))
    bad = d / "spk0_99.ema"
    bad.write_bytes(b"this is not an EST track\n")
    paths.insert(3, str(bad))
    return paths


def _import(paths, out, *extra):
    return main(["import", *paths, "-o", str(out), "-q", "--resample", "native", "--register", "none",
                 "--speaker-from", "prefix", "--points", "UL,LL", *extra])


def test_an_unreadable_input_stops_the_import_without_skip_bad(inputs, tmp_path, capsys):
    for jobs in ("1", "2"):
        out = tmp_path / f"x{jobs}.npz"
        assert _import(inputs, out, "--jobs", jobs) == 2
        err = capsys.readouterr().err
        assert f"cannot read {inputs[3]}: " in err and "1 of 7 inputs could not be read" in err, err
        assert "--skip-bad" in err and "nothing was written" in err
        assert not out.exists() and not list(tmp_path.glob(".*part*"))


def test_import_many_in_processes_skips_the_unreadable_file_with_its_reason(inputs, tmp_path, capsys):
    serial, pooled = tmp_path / "serial.npz", tmp_path / "pooled.npz"
    assert _import(inputs, serial, "--jobs", "1", "--skip-bad") == 0
    capsys.readouterr()
    assert _import(inputs, pooled, "--jobs", "2", "--skip-bad") == 0
    err = capsys.readouterr().err
    assert f"skipped {inputs[3]}: " in err and "read 6 of 7 inputs, skipped 1" in err
    reason = err.split(f"skipped {inputs[3]}: ", 1)[1].splitlines()[0]
    assert reason.strip()  # the reader's own message, not an empty line
    a, b = Corpus.load(serial), Corpus.load(pooled)
    good = [p for i, p in enumerate(inputs) if i != 3]
    assert [u.id for u in b.utterances] == [u.id for u in a.utterances] and len(b.utterances) == 6
    assert [u.stop - u.start for u in b.utterances] == [60 + 10 * i for i in range(6)]  # input order kept
    assert [u.speaker for u in b.utterances] == [p.rsplit("/", 1)[1].split("_")[0] for p in good]
    np.testing.assert_array_equal(a.frames, b.frames)


def test_import_many_on_dask_equals_in_process(inputs, tmp_path, capsys, dask_cluster):
    ref, out = tmp_path / "ref.npz", tmp_path / "dask.npz"
    assert _import(inputs, ref, "--jobs", "1", "--skip-bad") == 0
    assert _import(inputs, out, "--dask", dask_cluster.scheduler_address, "--skip-bad") == 0
    err = capsys.readouterr().err
    assert "Dask 2 workers" in err and f"skipped {inputs[3]}: " in err
    np.testing.assert_array_equal(Corpus.load(out).frames, Corpus.load(ref).frames)


def test_import_fails_when_no_input_is_readable(inputs, tmp_path, capsys):
    assert _import([inputs[3], inputs[3]], tmp_path / "x.npz", "--jobs", "1") == 2
    assert "none of the 2 inputs could be read (first: " in capsys.readouterr().err
    assert not (tmp_path / "x.npz").exists()
