"""engine.files.staging: a command's outputs are all written or none; an existing file is replaced only when asked;
errors name the user's file, never a temporary one. A full disk is simulated by making writes raise ENOSPC."""
import errno

import numpy as np
import pytest

from engine.files.atomic import atomic_write
from engine.files.staging import OutputExistsError, Outputs, user_path
from engine.io.writers.export import write_mesh_sequence, write_trajectory_csv


def _leftovers(d):
    return sorted(p.name for p in d.rglob(".*part*"))


def test_existing_files_are_refused_before_any_work_unless_forced(tmp_path):
    old = tmp_path / "t.csv"
    old.write_text("keep")
    with pytest.raises(OutputExistsError, match=r"t.csv \(-o\) already exists; nothing was written. Pass --force"):
        Outputs().file(old, option="-o")
    with Outputs(force=True) as out:
        write_trajectory_csv(out.file(old), np.zeros((3, 2)), rate=10)
    assert old.read_text().startswith("time,")
    assert not _leftovers(tmp_path)


def test_a_failure_or_a_stop_leaves_the_old_outputs(tmp_path):
    old, folder = tmp_path / "t.csv", tmp_path / "mesh"
    old.write_text("keep")
    for stop in (ValueError("boom"), KeyboardInterrupt()):
        with pytest.raises(type(stop)):
            with Outputs(force=True) as out:
                write_trajectory_csv(out.file(old), np.zeros((3, 2)), rate=10)
                write_mesh_sequence(out.folder(folder, pattern="frame_*.obj", exclusive=True), np.zeros((4, 9)))
                raise stop
        assert old.read_text() == "keep" and not folder.exists() and not _leftovers(tmp_path)


def test_an_exclusive_folder_holds_exactly_the_new_sequence(tmp_path):
    folder = tmp_path / "mesh"
    write_mesh_sequence(folder, np.zeros((6, 9)))
    (folder / "notes.txt").write_text("mine")
    with pytest.raises(OutputExistsError, match=r"frame_00000.obj and 5 other files \(--mesh-dir\)"):
        Outputs().folder(folder, pattern="frame_*.obj", exclusive=True, option="--mesh-dir")
    with Outputs(force=True) as out:
        write_mesh_sequence(out.folder(folder, pattern="frame_*.obj", exclusive=True), np.ones((3, 9)))
    assert sorted(p.name for p in folder.iterdir()) == ["frame_00000.obj", "frame_00001.obj", "frame_00002.obj",
                                                        "notes.txt"]
    # a folder of other files (audio beside recordings): only the same names count
    (folder / "a.wav").write_text("mine")
    with Outputs() as out:
        (out.folder(folder, pattern="*.wav", names=["b.wav"]) / "b.wav").write_text("new")
    assert (folder / "a.wav").read_text() == "mine" and (folder / "b.wav").read_text() == "new"
    with pytest.raises(OutputExistsError, match="a.wav"):
        Outputs().folder(folder, pattern="*.wav", names=["a.wav"])
    with pytest.raises(OutputExistsError, match="b.wav"):  # appeared while the work ran: refused at commit
        with Outputs() as out:
            (out.folder(folder, pattern="*.wav") / "b.wav").write_text("newer")
    assert (folder / "b.wav").read_text() == "new" and not _leftovers(tmp_path)


def test_a_commit_that_fails_part_way_is_rolled_back(tmp_path, monkeypatch):
    a, b = tmp_path / "a.csv", tmp_path / "sub" / "b.csv"
    a.write_text("old a")
    import engine.files.staging as staging

    real, calls = staging.move_noreplace, []

    def flaky(src, dst):
        calls.append(dst)
        if str(dst) == str(b):  # the second output cannot be moved in (disk full)
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(staging, "move_noreplace", flaky)
    with pytest.raises(OSError, match="No space left") as e:
        with Outputs(force=True) as out:
            out.file(a).write_text("new a")
            out.file(b).write_text("new b")
    monkeypatch.setattr(staging, "move_noreplace", real)
    assert e.value.filename == str(b)
    assert a.read_text() == "old a" and not b.exists() and not _leftovers(tmp_path)


def test_a_full_disk_names_the_users_file(tmp_path, monkeypatch):
    """ENOSPC from a writer, inside atomic_write and inside a staged output: the user's name, nothing left."""
    target = tmp_path / "t.csv"

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np, "savetxt", full)
    with pytest.raises(OSError) as e:
        write_trajectory_csv(target, np.zeros((3, 2)), rate=10)
    assert e.value.errno == errno.ENOSPC and e.value.filename == str(target)
    with pytest.raises(OSError) as e:
        with Outputs() as out:
            write_trajectory_csv(out.file(target), np.zeros((3, 2)), rate=10)
    assert e.value.filename == str(target) and not target.exists() and not _leftovers(tmp_path)
    ro = tmp_path / "ro"
    ro.mkdir()
    monkeypatch.setattr("tempfile.mkstemp", lambda **k: (_ for _ in ()).throw(
        PermissionError(errno.EACCES, "Permission denied", str(ro / ".x.abc.part.csv"))))
    with pytest.raises(PermissionError) as e:
        with atomic_write(ro / "x.csv"):
            pass
    assert e.value.filename == str(ro / "x.csv")


def test_user_path_maps_temporary_names(tmp_path):
    out = Outputs()
    f = out.file(tmp_path / "t.npz")
    d = out.folder(tmp_path / "aud")
    assert user_path(f) == str(tmp_path / "t.npz") and user_path(d / "x.wav") == str(tmp_path / "aud" / "x.wav")
    assert user_path("/elsewhere/y") == "/elsewhere/y"
    out.discard()
    assert user_path(f) == str(f) and not _leftovers(tmp_path)


def test_folders_made_for_outputs_that_never_land_are_removed(tmp_path):
    with pytest.raises(RuntimeError):
        with Outputs() as out:
            out.file(tmp_path / "a" / "b" / "t.csv").write_text("x")
            out.folder(tmp_path / "a" / "c" / "mesh")
            raise RuntimeError("the work failed")
    assert list(tmp_path.iterdir()) == []
    with Outputs() as out:
        out.file(tmp_path / "a" / "b" / "t.csv").write_text("x")
    assert (tmp_path / "a" / "b" / "t.csv").read_text() == "x"
