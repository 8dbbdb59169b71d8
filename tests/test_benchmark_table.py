"""The benchmark harness's JSON record and history, and the README table made from the history
(benchmarks/_harness.py, tools/benchmark_table.py)."""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "benchmarks"), str(REPO / "tools")]

import benchmark_table as bt  # noqa: E402
from _harness import HISTORY, Harness, append_history, read_history  # noqa: E402


def _record(name, date, figures, headline=(), argv=(), **kw):
    return {"benchmark": name, "date": date, "commit": kw.get("commit", "abc1234"), "dirty": False,
            "argv": list(argv), "params": {}, "machine": {"cpus": 2},
            "blas": {"libraries": [{"api": "openblas", "kernel": "Haswell", "threads": 2, "version": "0.3"}],
                     "openblas_env": kw.get("env", {})},
            "load": {"start": [1.0, 1.0, 1.0], "end": [2.0, 1.0, 1.0], "min1": 1.0, "max1": 2.0,
                     "steal_share": kw.get("steal")},
            "wall_s": 3.0, "peak_rss_mib": 100.0, "figures": figures, "headline": list(headline), "facts": {}}


def _fig(values, *, warm=0, cold=None, unit="s", rss=None):
    vals = list(values)
    over = vals[1:] if warm else vals
    f = {"values": vals, "unit": unit, "n": len(vals), "n_warm": warm, "min": min(over),
         "median": sorted(over)[len(over) // 2]}
    if warm:
        f["first"] = vals[0]
    if cold is not None:
        f["cold"] = cold
    if rss is not None:
        f["peak_rss_mib"] = rss
    return f


@pytest.fixture
def history(tmp_path):
    """A made-up history: bench_a twice (the later run must win), bench_b once with no headline."""
    recs = [
        _record("bench_a", "2026-01-01T10:00:00Z", {"fit": _fig([9.0], cold=True)}, ["fit"], commit="old0000"),
        _record("bench_b", "2026-01-01T11:00:00Z",
                {"setup": _fig([0.5]), "query": _fig([0.030, 0.010, 0.012, 0.011], warm=3, cold=True, rss=250.0)},
                argv=["--repeats", "3", "--json", "/tmp/x.json", "--no-history"], steal=0.021),
        _record("bench_a", "2026-01-02T10:00:00Z", {"fit": _fig([2.0, 2.5, 3.0], cold=True),
                                                    "rate": _fig([30.0, 40.0], unit="frames/s")},
                ["fit", "rate"], argv=["--preset", "small"], commit="new1111",
                env={"OPENBLAS_CORETYPE": "Haswell"}),
    ]
    path = tmp_path / "history.jsonl"
    for r in recs:
        append_history(r, path)
    return path


def test_table_takes_the_latest_record_of_each_benchmark(history):
    recs = read_history(history)
    assert [r["benchmark"] for r in recs] == ["bench_a", "bench_b", "bench_a"]
    last = bt.latest(recs)
    assert list(last) == ["bench_a", "bench_b"] and last["bench_a"]["commit"] == "new1111"
    rows = [ln for ln in bt.table(recs).splitlines() if ln.startswith("| `")]
    assert len(rows) == 3  # bench_a's two headline figures, bench_b's last figure
    fit, rate, query = rows
    assert fit.startswith("| `bench_a.py --preset small` | fit | 2.00 s / 2.50 s | 3 cold |")
    assert "new1111, 2026-01-02 10:00" in fit and "old0000" not in bt.table(recs)
    assert "Haswell; OPENBLAS_* CORETYPE=Haswell" in fit and "1.0–2.0" in fit
    assert "| rate | 30 frames/s / 40 frames/s | 2 runs |" in rate
    # the record options are not part of the command as run; warm figures say so, with the first call
    assert query.startswith("| `bench_b.py --repeats 3` | query | 10.0 ms / 11.0 ms; first 30.0 ms | "
                            "cold first call + 3 warm | 250 MiB |")
    assert "steal 2.1 %" in query and "setup" not in bt.table(recs)


def test_replace_table_keeps_the_rest_of_the_file_and_refuses_missing_markers():
    text = f"intro\n{bt.BEGIN}\nold rows\n{bt.END}\nafter\n"
    assert bt.replace_table(text, "NEW") == f"intro\n{bt.BEGIN}\nNEW\n{bt.END}\nafter\n"
    with pytest.raises(ValueError, match="README.md: expected one"):
        bt.replace_table("no markers here", "NEW", where="README.md")
    with pytest.raises(ValueError, match="expected one"):
        bt.replace_table(f"{bt.END}\n{bt.BEGIN}", "NEW")


def test_read_history_names_the_bad_line(tmp_path):
    p = tmp_path / "h.jsonl"
    p.write_text('{"benchmark": "a", "figures": {}}\nnot json\n')
    with pytest.raises(ValueError, match=r"h\.jsonl:2: not a JSON record"):
        read_history(p)
    p.write_text('{"figures": {}}\n')
    with pytest.raises(ValueError, match=r"h\.jsonl:1: expected a JSON object with a 'benchmark' field"):
        read_history(p)


def test_harness_record_appended_to_the_history(tmp_path, monkeypatch):
    monkeypatch.delenv("LIPSPACE_BENCH_NO_HISTORY", raising=False)
    path = tmp_path / "history.jsonl"
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=3)
    Harness.add_arguments(ap)
    args = ap.parse_args(["--json", str(tmp_path / "run.json")])
    bench = Harness("bench_made_up", args, history=path, quiet=True)
    calls = []
    out, m = bench.measure("append", lambda: calls.append(1) or len(calls), repeat=4, cold=True, headline=True)
    assert out == 5 and len(calls) == 5 and len(m.values) == 5 and len(m.warm) == 4
    assert m.min == min(m.values[1:]) and m.peak_traced_mib is not None and m.peak_rss_mib > 0
    bench.figure("rate", [10.0, 20.0, 30.0], "frames/s")
    bench.fact(frames=3)
    rec = bench.finish()
    line = path.read_text().splitlines()
    assert len(line) == 1 and json.loads(line[0]) == rec == json.loads((tmp_path / "run.json").read_text())
    assert rec["benchmark"] == "bench_made_up" and rec["params"] == {"size": 3}
    assert rec["headline"] == ["append"] and rec["facts"] == {"frames": 3}
    f = rec["figures"]["append"]
    assert f["n"] == 5 and f["n_warm"] == 4 and f["cold"] is True and f["first"] == m.values[0]
    assert rec["figures"]["rate"]["median"] == 20.0 and "first" not in rec["figures"]["rate"]
    assert set(rec["load"]) == {"start", "end", "min1", "max1", "steal_share"}
    assert {"libraries", "openblas_env"} <= set(rec["blas"]) and rec["machine"]["cpus"] == os.cpu_count()
    assert rec["date"].endswith("Z") and "commit" in rec and "dirty" in rec
    # --no-history, or the environment variable, keeps the history untouched
    args = ap.parse_args(["--no-history"])
    Harness("bench_made_up", args, history=path, quiet=True).finish()
    monkeypatch.setenv("LIPSPACE_BENCH_NO_HISTORY", "1")
    Harness("bench_made_up", None, history=path, quiet=True).finish()
    assert len(path.read_text().splitlines()) == 1


def test_harness_children_are_cold_figures(tmp_path):
    bench = Harness("bench_made_up", None, history=tmp_path / "h.jsonl", quiet=True)
    child = [sys.executable, "-c",
             "import json; print('noise'); print(json.dumps({'wall_s': 0.5, 'max_rss_MiB': 12.0}))"]
    rows = bench.children("child", child, repeat=2, headline=True)
    assert rows == [{"wall_s": 0.5, "max_rss_MiB": 12.0}] * 2
    f = bench.record()["figures"]["child"]
    assert f["values"] == [0.5, 0.5] and f["cold"] is True and f["peak_rss_mib"] == 12.0 and "first" not in f
    with pytest.raises(SystemExit, match="failed"):
        bench.children("bad", [sys.executable, "-c", "raise SystemExit(3)"])


def test_harness_refuses_a_figure_named_twice(tmp_path):
    bench = Harness("bench_made_up", None, history=tmp_path / "h.jsonl", quiet=True)
    bench.figure("x", 1.0)
    bench.figure("x", 2.0)
    with pytest.raises(ValueError, match=r"figures named twice: \['x'\]"):
        bench.finish()
    with pytest.raises(ValueError, match="'y': no values"):
        bench.figure("y", [])


def test_readme_table_is_generated_from_the_committed_history():
    recs = read_history(HISTORY)
    assert recs, "benchmarks/history.jsonl holds no record"
    new = bt.table(recs)
    for path in bt.TARGETS:
        text = path.read_text(encoding="utf-8")
        if bt.BEGIN in text or path.name == "README.md":
            assert bt.replace_table(text, new, where=str(path)) == text, \
                f"{path.name}: the benchmark table differs from benchmarks/history.jsonl; run tools/benchmark_table.py"
