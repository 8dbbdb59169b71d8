"""Issue 45's data-loss, memory and partial-output classes at the level of the files layer: the bounded
reader, moving files in without replacing, every output checked against the others and the inputs,
staging left by a dead process, and the cache's ownership markers."""
from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest

from engine.files.bounded import InputTooLargeError, NotRegularFileError, parse_json, read_bounded
from engine.files.ownership import mark, owned
from engine.files.placing import BACKUP_PREFIX, move_noreplace, output_kind, recover_stale
from engine.files.staging import OutputClashError, OutputExistsError, OutputRefusedError, Outputs


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


# ------------------------------------------------------------------ the bounded reader
def test_the_bounded_reader_refuses_what_is_not_a_small_regular_file(tmp_path):
    fifo = tmp_path / "f"
    os.mkfifo(fifo)
    with pytest.raises(NotRegularFileError, match="is a pipe"):  # never opened: no hang
        read_bounded(fifo)
    zero = tmp_path / "z"
    zero.symlink_to("/dev/zero")
    with pytest.raises(NotRegularFileError, match="is a device"):
        read_bounded(zero)
    big = tmp_path / "big.csv"
    with open(big, "wb") as fh:
        fh.truncate(6 * 2**30)  # sparse: costs nothing on disk
    with pytest.raises(InputTooLargeError, match=r"big.csv: 6.4 GB is more than can be read here \(at most 1.0 kB"):
        read_bounded(big, limit=1000)
    (tmp_path / "ok").write_bytes(b"abc")
    assert read_bounded(tmp_path / "ok", limit=3) == b"abc"
    with pytest.raises(FileNotFoundError):
        read_bounded(tmp_path / "missing")


def test_json_nested_too_deeply_is_a_value_error():
    with pytest.raises(ValueError, match="s.json: nested too deeply"):
        parse_json("[" * 100_000 + "]" * 100_000, source="s.json")
    with pytest.raises(ValueError, match="s.json: not valid JSON"):
        parse_json("{pid", source="s.json")


def test_a_6_gb_recording_is_refused_naming_it_and_the_limit(tmp_path):
    from engine.io import ImportFormatError, read_corpus

    big = tmp_path / "big.csv"
    with open(big, "wb") as fh:
        fh.truncate(6 * 2**30)
    with pytest.raises(ImportFormatError, match=r"big.csv: 6.4 GB is more than can be read here \(at most .*Split"):
        read_corpus(big)


# ------------------------------------------------------------------ moving in without replacing
def test_move_noreplace_never_replaces_a_file_or_a_link(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.write_text("new")
    b.write_text("the user's")
    with pytest.raises(FileExistsError):
        move_noreplace(a, b)
    assert b.read_text() == "the user's" and a.exists()
    dangling = tmp_path / "l"
    dangling.symlink_to(tmp_path / "nowhere")
    with pytest.raises(FileExistsError):
        move_noreplace(a, dangling)
    move_noreplace(a, tmp_path / "c")
    assert (tmp_path / "c").read_text() == "new" and not a.exists()
    assert output_kind(dangling) == "link" and output_kind(tmp_path / "c") == "file" and output_kind(tmp_path) == \
        "directory" and output_kind(tmp_path / "none") is None


def test_a_file_that_appears_while_the_command_runs_is_kept(tmp_path):
    """The 'already exists' check ran only at the start: a file written meanwhile was replaced."""
    out = tmp_path / "m.npz"
    with pytest.raises(OutputExistsError, match="appeared while the command ran"):
        with Outputs() as o:
            o.file(out).write_bytes(b"new manifold")
            out.write_bytes(b"the user's")  # written by someone else meanwhile
    assert out.read_bytes() == b"the user's" and sorted(p.name for p in tmp_path.iterdir()) == ["m.npz"]


@pytest.mark.parametrize("force", [False, True])
def test_pipes_devices_and_dangling_links_are_never_replaced(tmp_path, force):
    fifo = tmp_path / "f.csv"
    os.mkfifo(fifo)
    dev = tmp_path / "n.csv"
    dev.symlink_to("/dev/null")
    with pytest.raises(OutputRefusedError, match="is a pipe"):
        Outputs(force=force).file(fifo)
    with pytest.raises(OutputRefusedError, match="is a device"):
        Outputs(force=force).file(dev)
    dangling = tmp_path / "d.csv"
    dangling.symlink_to(tmp_path / "gone.csv")
    if not force:
        with pytest.raises(OutputExistsError):
            Outputs().file(dangling)
    assert output_kind(fifo) == "a pipe (FIFO)" and dev.is_symlink() and dangling.is_symlink()


def test_outputs_are_checked_against_each_other_and_the_inputs(tmp_path):
    inp = tmp_path / "t.csv"
    inp.write_text("0 0.1 p\n")
    with pytest.raises(OutputClashError, match=r"written twice \(by -o and by --praat\)"):
        with Outputs() as o:
            o.file(tmp_path / "out.csv", option="-o")
            o.file(tmp_path / "out.csv", option="--praat")
    with pytest.raises(OutputClashError, match=r"is also an input of the command \(--textgrid"):
        with Outputs(force=True, inputs=[("--textgrid", inp)]) as o:
            o.file(tmp_path / "t.csv", option="--praat")
    link = tmp_path / "link.csv"
    link.symlink_to(inp)
    with pytest.raises(OutputClashError, match="is also an input"):
        Outputs(force=True, inputs=[("CORPUS", link)]).file(inp)
    frames = tmp_path / "frames"
    frames.mkdir()
    (frames / "frame_00001.obj").write_text("v 0 0 0\n")
    with pytest.raises(OutputClashError, match="is also an input"):  # the sequence folder would remove it
        Outputs(force=True, inputs=[("--template", frames / "frame_00001.obj")]).folder(
            frames, pattern="frame_*.obj", exclusive=True)
    with pytest.raises(OutputClashError, match="written twice"):  # a file inside a folder another output fills
        with Outputs() as o:
            o.folder(tmp_path / "figs", names=["scree.png"], option="-o")
            o.file(tmp_path / "figs" / "scree.png", option="--csv")
    assert inp.read_text() == "0 0.1 p\n" and not list(tmp_path.glob(".*part*"))


# ------------------------------------------------------------------ what a killed process left
def test_staging_left_by_a_dead_process_is_cleared_by_the_next_run(tmp_path):
    dead, now = _dead_pid(), os.getpid()
    stale_dir = tmp_path / f".tg.part-{dead}-abc123"
    stale_dir.mkdir()
    (stale_dir / "u1.TextGrid").write_text("half")
    stale_file = tmp_path / f".t.part-{dead}-x1y2z3.csv"
    stale_file.write_text("half")
    nested = tmp_path / f"..t.part-{dead}-q.p{dead}-abcdefgh.part.csv"  # the atomic writer's, inside a staged one
    nested.write_text("half")
    live = tmp_path / f".t.part-{now}-live.csv"  # this process's own, still writing
    live.write_text("busy")
    old_format = tmp_path / ".t.part-zzz.csv"  # an older Lipspace's name (no pid): removed once an hour old
    old_format.write_text("x")
    t = time.time() - 7200
    os.utime(old_format, (t, t))
    other = tmp_path / f".u.part-{dead}-abc.csv"  # another output's: left for its own next run
    other.write_text("x")
    with Outputs() as o:
        o.file(tmp_path / "t.csv").write_text("new")
        o.folder(tmp_path / "tg", names=["u1.TextGrid"])
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted([live.name, other.name, "t.csv", "tg"]), left


def test_a_replacement_a_dead_process_left_half_done_is_put_back(tmp_path):
    from engine.files.placing import StagingWarning

    dead = _dead_pid()
    backup = tmp_path / f"{BACKUP_PREFIX}{dead}-abc"
    backup.mkdir()
    (backup / "a.csv").write_text("the user's old a")  # moved aside, its new file never landed
    (backup / "b.csv").write_text("old b")  # its new file landed: the old one is obsolete
    (tmp_path / "b.csv").write_text("new b")
    with pytest.warns(StagingWarning, match="a.csv was put back"):
        assert recover_stale(tmp_path, ["x"]) == [str(tmp_path / "a.csv")]
    assert (tmp_path / "a.csv").read_text() == "the user's old a" and (tmp_path / "b.csv").read_text() == "new b"
    assert not backup.exists()


# ------------------------------------------------------------------ the cache's own entries
def test_an_entry_is_owned_only_while_it_is_the_file_that_was_marked(tmp_path):
    e = tmp_path / "manifolds" / "synthetic-small-x.npz"
    e.parent.mkdir()
    e.write_bytes(b"entry")
    assert not owned(e, tmp_path)
    assert mark(e, tmp_path) and owned(e, tmp_path)
    e.write_bytes(b"the user's, copied over it")
    assert not owned(e, tmp_path)
    lnk = tmp_path / "synthetic-small-link.npz"
    lnk.symlink_to(e)
    assert not mark(lnk, tmp_path) and not owned(lnk, tmp_path)  # a link is never an entry
