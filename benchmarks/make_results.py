"""Generate docs/RESULTS.md: the equal-information protocol tables from the current code.

Usage: python benchmarks/make_results.py [--out docs/RESULTS.md] [--preset default|small] [--seed 0]
                                         [--haskins-dir DIR] [--cache-dir DIR]

Sections (every number in the file is computed by this run):

1. the default synthetic talker (``--preset``, 10 % of the utterances held out, seed 0);
2. the held-out synthetic talker (:data:`engine.synthetic.HELD_OUT_TALKER`, same preset
   and split rule), never used to tune anything;
3. the Haskins IEEE pair (two speakers, one sentence each): cross-speaker in both
   directions, with each speaker's mean frame removed, and once without that removal
   to show what the raw cross-speaker figures measure.

Settings (state dims, smoothing, k) are chosen per corpus on a validation split of its
training utterances (:func:`engine.protocols.select_settings`). Prints wall time and
peak memory of each section and the BLAS in use. Measured: 12-18 minutes for the default
preset on two cores shared with other jobs (load average about 14; peak RSS 1.1 GB);
the small preset about 1.5 minutes on the same machine.
"""
from __future__ import annotations

import argparse
import datetime
import platform
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
from _common import peak_rss_mb  # noqa: E402
#: where the Haskins pair is looked for (the same place as ``lipspace evaluate --haskins``)
DEFAULT_HASKINS = REPO.parent / "shared" / "data" / "haskins-ieee"


def _blas():
    try:
        from threadpoolctl import threadpool_info

        return ", ".join(f"{i.get('internal_api')} {i.get('version')} ({i.get('num_threads')} threads)"
                         for i in threadpool_info())
    except Exception as exc:  # pragma: no cover - informational only
        return f"unknown ({exc})"


def _commit():
    """Short HEAD, marked when engine/ or app/ has uncommitted changes (the run imports those)."""
    try:
        head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--untracked-files=no", "--",
                                "engine", "app"], capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + (" (plus uncommitted changes in engine/ or app/)" if dirty else "")


def _summary_line(name, r):
    parts = []
    for p in r.protocols():
        ref = r.row(p, "manifold")
        for meas, lab in (("rmse_x", "X"), ("rmse_y", "Y3"), ("lve", "LVE")):
            better = [x["method"] for x in r.rows if x["protocol"] == p and x["method"] != "manifold"
                      and x[meas] < ref[meas]]
            parts.append("manifold best" if not better else "loses to " + ", ".join(better))
    return f"| {name} | " + " | ".join(parts[:3]) + " | " + " | ".join(parts[3:]) + " |"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(REPO / "docs" / "RESULTS.md"))
    ap.add_argument("--preset", default="default", choices=("small", "default"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--haskins-dir", default=str(DEFAULT_HASKINS))
    ap.add_argument("--cache-dir", default=None)
    args = ap.parse_args()

    from engine._atomic import atomic_write
    from engine.io import read_corpus
    from engine.protocols import evaluate_protocols
    from engine.synthetic import HELD_OUT_TALKER, load_synthetic

    t_all = time.perf_counter()
    commit = _commit()  # the code this run imports (taken before anything is computed)
    print(f"BLAS: {_blas()}", flush=True)
    sections, summary, timings = [], [], []

    def run(name, corpus, **kw):
        t = time.perf_counter()
        r = evaluate_protocols(corpus, random_state=args.seed, **kw)
        dt = time.perf_counter() - t
        timings.append((name, dt))
        print(f"{name}: {dt:.1f} s, max RSS {peak_rss_mb():.0f} MiB", flush=True)
        return r

    talkers = [("Default synthetic talker", {}),
               ("Held-out synthetic talker", dict(HELD_OUT_TALKER))]
    for title, params in talkers:
        corpus = load_synthetic(preset=args.preset, cache_dir=args.cache_dir, **params)
        r = run(title, corpus)
        desc = ", ".join(f"{k}={v}" for k, v in params.items()) or "the generator's defaults"
        r.notes.append(f"talker: preset `{args.preset}`, {desc}; {corpus.n_frames} frames at {corpus.rate:g} Hz")
        sections.append(r.markdown(title=f"{title} (preset `{args.preset}`)"))
        sections.append(_validation_table(r))
        summary.append(_summary_line(f"{title}", r))

    hdir = Path(args.haskins_dir)
    mats = sorted(hdir.glob("*.mat"))
    if len(mats) >= 2:
        from app.cli.evaluate import haskins_speaker, name_haskins_speakers, normalise_per_speaker

        raw = name_haskins_speakers(read_corpus([str(p) for p in mats]))
        norm = normalise_per_speaker(raw)
        ids = [u.id for u in raw.utterances]
        for test in ids:
            who = haskins_speaker(raw.utterance(test))
            r = run(f"Haskins, test {who}", norm, test_ids=[test])
            r.notes.append("per-speaker mean frame removed (engine.registration.normalise_speakers, mode 'mean', "
                           "speakers named by the file name's first field)")
            sections.append(r.markdown(title=f"Haskins pair, cross-speaker: test speaker {who}, speaker means removed"))
            summary.append(_summary_line(f"Haskins, test {who} (normalised)", r))
        test = ids[1]
        r = run("Haskins raw", raw, test_ids=[test], inverse_table=False)
        r.notes.append("no speaker normalisation: the figures are dominated by the offset between the speakers' "
                       f"mean frames ({_offset(raw):.3g} mm RMS per coordinate); compare the mean-frame row")
        sections.append(r.markdown(title=f"Haskins pair, cross-speaker without normalisation: test speaker "
                                         f"{haskins_speaker(raw.utterance(test))}"))
        summary.append(_summary_line(f"Haskins, test {haskins_speaker(raw.utterance(test))} (raw)", r))
    else:
        sections.append(f"### Haskins pair\n\nNot run: no Haskins samples (*.mat) in {hdir.name}/.\n")

    total = time.perf_counter() - t_all
    head = [
        "# Results: held-out synthesis under equal information",
        "",
        f"Generated by `benchmarks/make_results.py` at commit `{commit}` on "
        f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC ({platform.machine()}, Python "
        f"{platform.python_version()}); total {total:.0f} s. Regenerate with "
        "`.venv/bin/python benchmarks/make_results.py`. Do not edit by hand.",
        "",
        "How to read the tables (docs/METHOD.md gives the method and every decision):",
        "",
        "- **Protocol `states`**: every method gets only the target states (the state of each phone "
        "mid-point frame of the held-out utterance). `manifold`: Viterbi path between them, X from each "
        "state's mean F^x, smoothed. `manifold-ll`: the same path's centroids smoothed in Y and mapped through "
        "the local-linear inverse. `linear`, `pchip`, `hermite`: interpolation through the states' mean X "
        "(Hermite also gets each state's mean velocity).",
        "- **Protocol `oracle`**: every method gets the true X at the targets and the target states. "
        "The manifold paths are anchored to the true X at the targets; the interpolations pass through it; "
        "`unitselection` uses the phones and their times.",
        "- **`mean-frame`**: the training corpus's mean frame, held throughout.",
        "- **RMSE X**: RMS over frames of the Euclidean error in the shape space X (corpus units, mm). "
        "**RMSE Y3**: the same in the first 3 dims of Y, every trajectory (the manifold's too) projected "
        "through the same fitted pipeline. **LVE**: lip-vertex error, per frame the largest per-point "
        "Euclidean error (mm), averaged over frames. Scored from the first to the last target.",
        "- **ΔX vs manifold**: mean over utterances of (method's RMSE X − manifold's), with a 95 % "
        "bootstrap interval; positive means the manifold erred less. **manifold wins X**: utterances on "
        "which the manifold's RMSE X is lower; **p (sign)**: two-sided sign test.",
        "- Each table's verdict lines name every method that beats the manifold.",
        "",
        "## Summary",
        "",
        "| corpus | states X | states Y3 | states LVE | oracle X | oracle Y3 | oracle LVE |",
        "|---|---|---|---|---|---|---|",
        *summary,
        "",
        "Run times: " + "; ".join(f"{n} {t:.0f} s" for n, t in timings) + f". BLAS: {_blas()}.",
        "",
    ]
    text = "\n".join(head) + "\n" + "\n".join(sections) + "\n"
    with atomic_write(args.out) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    print(f"wrote {args.out} in {total:.0f} s; max RSS {peak_rss_mb():.0f} MiB")


def _offset(corpus):
    """RMS per coordinate of the difference between the first two speakers' mean frames."""
    import numpy as np

    spk = np.array([u.speaker for u in corpus.utterances])[corpus.utterance_index]
    a, b = corpus.speakers[:2]
    d = corpus.frames[spk == a].mean(axis=0, dtype=np.float64) - corpus.frames[spk == b].mean(axis=0, dtype=np.float64)
    return float(np.sqrt(np.mean(d ** 2)))


def _validation_table(r) -> str:
    v = r.settings.get("validation", {})
    if not v:
        return ""
    sig = sorted({float(k.rsplit("/", 1)[1]) for t in v.values() for k in t["rmse_x"]})
    out = ["#### Validation (training utterances only): `manifold` RMSE X, states protocol", "",
           "| state dims | frames per state | K | k (local-linear) | local-linear RMSE X | " +
           " | ".join(f"σ = {s:g}" for s in sig) + " |", "|" + "---|" * (5 + len(sig))]
    for t in v.values():
        cells = [f"{t['rmse_x'][f'states/manifold/{s:g}']:.3f}" for s in sig]
        out.append(f"| {t['dims']} | {t['frames_per_state']} | {t['K']} | {t['k']} | {t['k_errors'][t['k']]:.3f} | "
                   + " | ".join(cells) + " |")
    s = r.settings
    out += ["", f"Chosen: state dims {s['state_dims']}, one state per {s['frames_per_state']} frames, k "
                f"{s['n_neighbors']}, smoothing " + ", ".join(f"{k} {x:g}" for k, x in s["sigma"].items())
                + f" ({s['note']}).", ""]
    return "\n".join(out)


if __name__ == "__main__":
    main()
