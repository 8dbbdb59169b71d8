"""The third bad-input campaign (issue 45), its fast cases: the command line's side.

Every option is checked as it is parsed and named in the refusal; every output of a command is
checked against its other outputs and its inputs, also the ones it derives; a full or closed
standard stream never fails a finished command; a display with nothing behind it is said.
``benchmarks/campaign_bad_input.py`` runs these and the slow ones as real processes."""
from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from app.cli import main

PHONES = "p 0.1 aa 0.1"


@pytest.fixture(scope="module")
def mfile(tiny_manifold_file):
    return tiny_manifold_file


def _one_line(capsys):
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


# ------------------------------------------------------------------ class 1: no output over another, or an input
def test_the_praat_table_and_o_naming_one_file_are_refused(mfile, tmp_path, capsys):
    tg = tmp_path / "in.lab"
    tg.write_text("0 0.1 p\n0.1 0.3 aa\n")
    out = tmp_path / "out.csv"
    assert main(["synthesize", "--manifold", str(mfile), "--textgrid", str(tg),
                 "--praat", str(tmp_path / "out.TextGrid"), "-o", str(out), "--method", "linear", "-q"]) == 2
    assert "would be written twice (by -o and by --praat)" in _one_line(capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.lab"]


def test_the_praat_table_over_its_own_textgrid_input_is_refused_with_force(mfile, tmp_path, capsys):
    t = tmp_path / "t.csv"
    t.write_text("0 0.1 p\n0.1 0.3 aa\n0.3 0.5 m\n")
    assert main(["synthesize", "--manifold", str(mfile), "--textgrid", str(t), "--praat", str(tmp_path / "t.TextGrid"),
                 "--force", "--method", "linear", "-q"]) == 2
    assert "is also an input of the command (--textgrid" in _one_line(capsys)
    assert t.read_text() == "0 0.1 p\n0.1 0.3 aa\n0.3 0.5 m\n"


def test_two_output_options_naming_one_file_are_refused(mfile, tmp_path, capsys):
    corpus = Path(mfile).with_name("corpus.npz")
    r = tmp_path / "r.csv"
    assert main(["evaluate", str(corpus), "--csv", str(r), "--markdown", str(r), "-q"]) == 2
    assert "--csv and --markdown both name" in _one_line(capsys) and not r.exists()


def test_an_existing_quality_report_is_refused_as_an_output_not_as_an_input(tmp_path, capsys):
    lips = tmp_path / "lips.csv"
    lips.write_text("time,UL_x,UL_y,LL_x,LL_y\n" + "".join(f"{k / 100:.2f},1,2,{k % 5},-3\n" for k in range(60)))
    report = tmp_path / "r.csv"
    report.write_text("the user's own table\n")
    argv = ["import", str(lips), "-o", str(tmp_path / "c.npz"), "-q", "--quality-report", str(report)]
    assert main(argv) == 2
    err = _one_line(capsys)
    assert f"--quality-report {report}: already exists" in err and "--force" in err, err
    assert report.read_text() == "the user's own table\n" and not (tmp_path / "c.npz").exists()
    assert main(argv + ["--force"]) == 0
    assert report.read_text().startswith("utterance,sensor,measure") and (tmp_path / "c.npz").is_file()


def test_a_fifo_a_device_and_a_dangling_link_are_never_replaced(mfile, tmp_path, capsys):
    fifo = tmp_path / "f.csv"
    os.mkfifo(fifo)
    dev = tmp_path / "n.csv"
    dev.symlink_to("/dev/null")
    dangling = tmp_path / "d.csv"
    dangling.symlink_to(tmp_path / "gone" / "x.csv")
    for out, force, says in ((fifo, True, "is a pipe (FIFO)"), (dev, True, "is a device"),
                             (dangling, False, "already exists (a symbolic link)")):
        assert main(["synthesize", "--manifold", str(mfile), "--phones", PHONES, "-o", str(out), "--method", "linear",
                     "-q", *(["--force"] if force else [])]) == 2
        assert says in _one_line(capsys)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and dev.is_symlink() and dangling.is_symlink()


# ------------------------------------------------------------------ class 2: stored paths stay in the corpus's folder
def test_a_stored_audio_path_outside_the_folder_is_not_copied(mfile, tmp_path, capsys):
    from engine.files.persist import read_npz

    (tmp_path / "private").mkdir()
    (tmp_path / "private" / "secret.wav").write_text("SECRET\n")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "notes.wav").write_text("not sound\n")
    d = read_npz(mfile)
    n = len(d["corpus_utt_ids"])
    d["corpus_utt_audio"] = np.array(["../private/secret.wav", "notes.wav"] + [""] * (n - 2))
    d["corpus_utt_audio_abs"] = np.array([""] * n)
    m = tmp_path / "sub" / "m.npz"
    with open(m, "wb") as fh:
        np.savez(fh, **d)
    ids = [str(x) for x in d["corpus_utt_ids"]]
    for uid, says in ((ids[0], "is outside the folder of m.npz"), (ids[1], "not a WAV file")):
        assert main(["synthesize", "--manifold", str(m), "--utterance", uid, "-o", str(tmp_path / "x.glb"),
                     "--method", "linear", "-q", "--force"]) == 0
        assert says in capsys.readouterr().err
        assert not (tmp_path / "x.wav").exists()


# ------------------------------------------------------------------ class 5: memory
def test_a_6_gb_input_is_refused_naming_the_file(tmp_path, capsys):
    big = tmp_path / "big.csv"
    with open(big, "wb") as fh:
        fh.truncate(6 * 2**30)
    assert main(["import", str(big), "-o", str(tmp_path / "c.npz")]) == 2
    err = _one_line(capsys)
    assert f"{big}: 6.4 GB is more than can be read here (at most" in err and "Import fewer files" not in err


# ------------------------------------------------------------------ class 7: empty, duplicated, unbounded options
@pytest.mark.parametrize("argv, says", [
    (["synthesize", "--manifold", "", "--phones", PHONES], "--manifold '': expected a value, not an empty string"),
    (["synthesize", "--manifold", "{m}", "--phones", PHONES, "-o", ""], "-o/--output '': expected a value"),
    (["synthesize", "--manifold", "{m}", "--phones", PHONES, "--mesh-dir", ""], "--mesh-dir '': expected a value"),
    (["clusters", "{m}", "--phones", ""], "--phones '': expected a comma-separated list of phones"),
    (["import", "{m}", "-o", "{tmp}/c.npz", "--points", "UL,UL"], "--points UL,UL: names UL twice"),
    (["import", "{m}", "-o", "{tmp}/c.npz", "--points", ""], "--points '': expected a comma-separated list"),
    (["evaluate", "{m}", "--test-ids", "a,a"], "--test-ids a,a: names a twice"),
    (["synthesize", "--manifold", "{m}", "--utterance", "u", "--key-frames", "0,,5"],
     "--key-frames 0,,5: holds an empty"),
    (["build", "-o", "{tmp}/m.npz", "--states", "0"], "--states 0: must be at least 1"),
    (["build", "-o", "{tmp}/m.npz", "--seed", "-1"], "--seed -1: must be from 0 to 4294967295"),
    (["build", "-o", "{tmp}/m.npz", "--seed", str(2**70)], f"--seed {2**70}: must be from 0 to 4294967295"),
    (["build", "-o", "{tmp}/m.npz", "--embedding-dims", "100000"], "--embedding-dims 100000: must be from 3 to 256"),
    (["build", "-o", "{tmp}/m.npz", "--variance", "0"], "--variance 0: must be above 0 and at most 1"),
    (["build", "-o", "{tmp}/m.npz", "--neighbors", "2"], "--neighbors 2: must be from 3"),
    (["synthesize", "--manifold", "{m}", "--phones", PHONES, "--candidates", "1e3"], "--candidates '1e3': expected a "
                                                                                       "whole number"),
    (["figures", "{m}", "-o", "{tmp}/f", "--dpi", "abc"], "--dpi 'abc': expected a number"),
    (["import", "{m}", "-o", "{tmp}/c.npz", "--quality-max-gap", "-1"], "--quality-max-gap -1: must be from 0 to "
                                                                         "1000 ms"),
    (["import", "{m}", "-o", "{tmp}/c.npz", "--quality-threshold", "0"], "--quality-threshold 0: must be above 0"),
    (["build", "-o", "{tmp}/m.npz", "--dynamics-scale", "p200"], "error: --dynamics-scale must be 'max' or a "
                                                                  "percentile"),
])
def test_every_option_is_checked_as_parsed_and_named(mfile, tmp_path, capsys, argv, says):
    argv = [a.format(m=mfile, tmp=tmp_path) for a in argv]
    assert main(argv) == 2
    err = _one_line(capsys)
    assert says in err, err
    for internal in ("n_states", "random_state", "None for the default", "concatenate", "too few"):
        assert internal not in err, err
    assert not list(tmp_path.iterdir())


def test_options_the_corpus_is_too_small_for_name_the_option(mfile, tmp_path, capsys):
    corpus = Path(mfile).with_name("corpus.npz")
    assert main(["build", str(corpus), "-o", str(tmp_path / "m.npz"), "--states", "100000", "-q"]) == 2
    assert "--states 100000: more states than" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


# ------------------------------------------------------------------ class 8: what the message blames
def test_an_unknown_command_is_named_not_taken_for_a_missing_display(capsys):
    assert main(["nosuchcommand"]) == 2
    err = _one_line(capsys)
    assert "unknown command 'nosuchcommand'" in err and "display" not in err
    assert main(["biuld"]) == 2
    assert "did you mean 'build'?" in _one_line(capsys)


def _run(shell, cwd, timeout=120):
    env = dict(os.environ, LIPSPACE=f"{sys.executable} -m app.cli")
    env.pop("DISPLAY", None)
    return subprocess.run(["sh", "-c", shell], capture_output=True, text=True, cwd=cwd, env=env, timeout=timeout)


def test_a_full_or_closed_standard_stream_never_fails_a_finished_command(mfile, tmp_path):
    out = tmp_path / "t.csv"
    r = _run(f'$LIPSPACE synthesize --manifold "{mfile}" --phones "{PHONES}" -o "{out}" --method linear -q '
             "> /dev/full", tmp_path)
    assert r.returncode == 0 and out.is_file(), r.stderr
    assert "standard output could not be written (No space left on device)" in r.stderr and "Traceback" not in r.stderr
    r = _run(f'$LIPSPACE info "{mfile}" >&-', tmp_path)
    assert r.returncode == 1 and "standard output could not be written" in r.stderr and "Traceback" not in r.stderr
    c = tmp_path / "c.npz"
    r = _run(f'$LIPSPACE import "{Path(mfile).with_name("corpus.npz")}" -o "{c}" 2>&-', tmp_path)
    assert r.returncode == 0 and c.is_file() and "wrote" in r.stdout


@pytest.mark.parametrize("env, says", [({"DISPLAY": ":57"}, "DISPLAY is ':57' but no X server listens"),
                                       ({"DISPLAY": "nonsense"}, "not of the form [host]:number"),
                                       ({"WAYLAND_DISPLAY": "wayland-57"}, "no compositor listens")])
def test_a_display_with_nothing_behind_it_is_said_and_exits_2(mfile, tmp_path, env, says):
    """Qt aborted the process with a core dump and 'Reinstalling the application may fix this problem'."""
    full = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    full.update(env, XDG_RUNTIME_DIR=str(tmp_path), LIPSPACE_STATE_DIR=str(tmp_path / "st"))
    r = subprocess.run([sys.executable, "-m", "app.cli", "explore", str(mfile)], capture_output=True, text=True,
                       env=full, timeout=120)
    assert r.returncode == 2 and says in r.stderr and "Traceback" not in r.stderr, r.stderr
    r = subprocess.run([sys.executable, "-m", "app.cli", "explore", str(tmp_path / "missing.npz")], capture_output=True,
                       text=True, env=full, timeout=120)
    assert r.returncode == 2 and "no such file" in r.stderr  # the file is said first


def test_the_display_check_without_a_display_server(tmp_path):
    from app.display_check import display_problem

    assert display_problem({}, "win32") is None and display_problem({"QT_QPA_PLATFORM": "offscreen"}, "linux") is None
    assert "no X server listens at /tmp/.X11-unix/X57" in display_problem({"DISPLAY": ":57"}, "linux")
    why = display_problem({"DISPLAY": ":57", "WAYLAND_DISPLAY": "w-9", "XDG_RUNTIME_DIR": str(tmp_path)}, "linux")
    assert "WAYLAND_DISPLAY is 'w-9'" in why and "DISPLAY is ':57'" in why


# ------------------------------------------------------------------ class 3 and 4: damaged files read back
def test_damaged_manifold_fields_are_refused_by_field(mfile, tmp_path, capsys):
    from engine.files.persist import read_npz

    deep = "[" * 100_000 + "]" * 100_000
    arrays = read_npz(mfile)
    names = arrays["corpus_point_names"].copy()
    names[1] = names[0]
    for change, says in (({"corpus_axes": np.array("x=up,y=up,z=up")}, "its axes 'x=up,y=up,z=up' are damaged"),
                         ({"manifold_params": np.array('{"n_states": ' + deep + "}")}, "'manifold_params': nested "
                                                                                       "too deeply"),
                         ({"states/__params__": np.array('{"n_states": ' + deep + "}")}, "nested too deeply"),
                         ({"Fy": arrays["Fy"].astype(np.complex64)}, "field 'Fy': expected float values"),
                         ({"corpus_point_names": names}, "points 1 and 2 are both named")):
        p = tmp_path / "bad.npz"
        with open(p, "wb") as fh:
            np.savez(fh, **{**arrays, **change})
        assert main(["info", str(p)]) == 2
        assert says in _one_line(capsys)


def test_a_label_over_two_lines_and_a_quoted_label_are_imported(mfile, tmp_path, capsys):
    csv = tmp_path / "lips.csv"
    csv.write_text("time,UL_x,UL_y,LL_x,LL_y\n" + "".join(f"{k / 100:.2f},{np.sin(k / 7):.4f},2,{k % 5},-3\n"
                                                           for k in range(60)))
    tg = tmp_path / "ml.TextGrid"
    tg.write_text('File type = "ooTextFile"\nObject class = "TextGrid"\n\nxmin = 0\nxmax = 0.6\ntiers? <exists>\n'
                  'size = 1\nitem []:\n    item [1]:\n        class = "IntervalTier"\n        name = "phones"\n'
                  '        xmin = 0\n        xmax = 0.6\n        intervals: size = 2\n        intervals [1]:\n'
                  '            xmin = 0\n            xmax = 0.3\n            text = "p\nb"\n        intervals [2]:\n'
                  '            xmin = 0.3\n            xmax = 0.6\n            text = "say ""hi"""\n')
    out = tmp_path / "c.npz"
    assert main(["import", str(csv), "--alignment", str(tg), "-o", str(out)]) == 0
    labels = [str(x) for x in np.load(out)["corpus_phone_labels"]]
    assert labels == ["p b", 'say "hi"']


def test_a_session_restored_from_a_damaged_autosave_is_set_aside_once(mfile, tmp_path):
    from app.files.autosave import Autosaver, resolve_recovery
    from app.files.session import SessionError

    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    a = tmp_path / "autosave"
    a.mkdir()
    (a / f"running-{p.pid}-5.json").write_text(json.dumps({"pid": p.pid, "started": 1.0}))
    (a / f"autosave-{p.pid}-5.lipspace.json").write_text(json.dumps({"lipspace_session": 2,
                                                                     "source": {"path": str(mfile)},
                                                                     "selection": "x"}))
    saver = Autosaver(a)
    rec = saver.begin()
    with pytest.raises(SessionError, match="field 'selection' must be an object.*moved to .*damaged"):
        resolve_recovery(saver, rec, restore=True)
    saver.finish()
    again = Autosaver(a)
    assert again.begin() is None and again.set_aside == []  # said once, never offered again
    again.finish()
