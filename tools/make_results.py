"""Generate docs/RESULTS.md: the equal-information protocol tables from the current code.

Usage: python tools/make_results.py [--out docs/RESULTS.md] [--preset default|small] [--seed 0]
                                         [--corpus default held-out haskins faces] [--haskins-dir DIR]
                                         [--faces-dir DIR] [--cache-dir DIR] [--results-cache DIR]
                                         [--speaker-norm mean|mean+scale]

Corpora (every number in the file is computed by this script from current code):

``default``   the default synthetic talker (``--preset``, 10 % of the utterances held out, seed 0);
``held-out``  the held-out synthetic talker (:data:`engine.talker.synthetic.HELD_OUT_TALKER`, same preset
              and split rule), never used to tune anything;
``haskins``   the Haskins IEEE pair (two speakers, one sentence each): cross-speaker in both
              directions with each speaker's mean frame removed, and once without that removal;
``faces``     the five real talking-face clips, each imported with ``lipspace import`` (60 Hz),
              pooled as one corpus of five speakers (each clip's mean frame removed), every clip
              held out in turn (leave one clip out) with kinematic key frames as targets.

``--speaker-norm mean+scale`` also scales each speaker's spread to the pooled spread in the two
real corpora (a sensitivity run: write it elsewhere with ``--out``; RESULTS.md is made with
``mean``, the default of ``lipspace build`` and ``evaluate``).

Settings are chosen per corpus (and per fold) on a validation split of its training
utterances (:func:`engine.evaluation.protocols.select_settings`). Each corpus's section is cached
(``--results-cache``, default ``<cache folder>/make-results``) with the commit and code
key that computed it: ``--corpus NAME ...`` recomputes only those and takes the others
from the cache (a section computed by other code is marked so in the file; run without
``--corpus`` to recompute everything). Prints wall time and peak memory of each corpus
and the BLAS in use.
"""
from __future__ import annotations

import argparse
import datetime
import json
import platform
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _common, beside the benchmarks
from _common import peak_rss_mb  # noqa: E402
from _results_tables import contribution_cells, contribution_table, summary_cells, summary_table  # noqa: E402

#: where the Haskins pair is looked for (the same place as ``lipspace evaluate --haskins``)
DEFAULT_HASKINS = REPO.parent / "shared" / "data" / "haskins-ieee"
DEFAULT_FACES = REPO.parent / "shared" / "data" / "talking-faces"
CORPORA = ("default", "held-out", "haskins", "faces")
#: per-speaker normalisations of the real corpora, and what a title adds for each
_SPREAD = {"mean": "", "mean+scale": ", spreads equalised"}
#: layout of a cached section; a section of another layout is recomputed
SECTION_FORMAT = 2
PROTOCOLS = ("states", "oracle", "phones")
#: code whose change makes a cached section stale
CODE = ("engine.evaluation.protocols", "engine.synthesis.protocol_methods", "engine.evaluation.protocol_report",
        "engine.synthesis.learnt_paths", "engine.synthesis.statepaths", "engine.synthesis.dominance",
        "engine.synthesis.sliding_window", "engine.synthesis.unitselection", "engine.synthesis.viterbi",
        "engine.graph.states", "engine.manifold.model", "engine.manifold.embedding", "engine.manifold.shape",
        "engine.manifold.dynamics", "engine.talker.synthetic", "engine.phonetics.targets",
        "engine.recordings.kinematics", "engine.evaluation.paired", "engine.recordings.registration",
        "engine.manifold.inverse_local")


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
                                "engine", "app", "tools"], capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + (" (plus uncommitted changes)" if dirty else "")


def _code_key():
    from engine.files.persist import source_fingerprint

    files = [REPO / "tools" / "make_results.py", REPO / "tools" / "_results_tables.py"]
    return source_fingerprint(CODE, {"scripts": [f.read_text(encoding="utf-8") for f in files]})


class Section:
    """One corpus's part of the file: Markdown, summary cells, validation choices, seconds."""

    def __init__(self, key):
        self.key, self.markdown, self.summary, self.lve, self.contribution, self.best = key, [], [], [], [], []
        self.seconds = 0.0

    def add(self, name, result, title, *, validation=True):
        self.markdown.append(result.markdown(title=title))
        if validation:
            self.markdown.append(_validation_table(result))
        self.summary.append((name, summary_cells(result, "rmse_x")))
        self.lve.append((name, summary_cells(result, "lve")))
        self.contribution.append((name, contribution_cells(result)))
        folds = result.folds or [result.settings]
        self.best.append((name, [f.get("best") or {} for f in folds]))

    def as_dict(self, commit, code):
        return {"key": self.key, "markdown": self.markdown, "summary": self.summary, "lve": self.lve,
                "contribution": self.contribution, "best": self.best, "seconds": self.seconds, "commit": commit,
                "code": code, "format": SECTION_FORMAT}


def _run(name, corpus, seed, **kw):
    from engine.evaluation.protocols import evaluate_protocols

    t = time.perf_counter()
    r = evaluate_protocols(corpus, random_state=seed, **kw)
    print(f"  {name}: {time.perf_counter() - t:.1f} s, max RSS {peak_rss_mb():.0f} MiB", flush=True)
    return r


def run_synthetic(key, args):
    from engine.talker.synthetic import HELD_OUT_TALKER, load_synthetic

    title, params = {"default": ("Default synthetic talker", {}),
                     "held-out": ("Held-out synthetic talker", dict(HELD_OUT_TALKER))}[key]
    sec = Section(key)
    corpus = load_synthetic(preset=args.preset, cache_dir=args.cache_dir, **params)
    r = _run(title, corpus, args.seed)
    desc = ", ".join(f"{k}={v}" for k, v in params.items()) or "the generator's defaults"
    r.notes.append(f"talker: preset `{args.preset}`, {desc}; {corpus.n_frames} frames at {corpus.rate:g} Hz")
    sec.add(title, r, f"{title} (preset `{args.preset}`)")
    return sec


def run_haskins(args):
    from app.cli.evaluate import haskins_speaker, name_haskins_speakers, normalise_per_speaker
    from engine.io import read_corpus

    sec = Section("haskins")
    mats = sorted(Path(args.haskins_dir).glob("*.mat"))
    if len(mats) < 2:
        sec.markdown.append("### Haskins pair\n\n"
                            f"Not run: no Haskins samples (*.mat) in {Path(args.haskins_dir).name}/.\n")
        return sec
    raw = name_haskins_speakers(read_corpus([str(p) for p in mats]))
    norm = normalise_per_speaker(raw, mode=args.speaker_norm)
    ids = [u.id for u in raw.utterances]
    for test in ids:
        who = haskins_speaker(raw.utterance(test))
        r = _run(f"Haskins, test {who}", norm, args.seed, test_ids=[test])
        r.notes.append(f"per-speaker mean frame removed (engine.recordings.registration.normalise_speakers, mode "
                       f"'{args.speaker_norm}', speakers named by the file name's first field)")
        sec.add(f"Haskins, test {who} (normalised)", r,
                f"Haskins pair, cross-speaker: test speaker {who}, speaker means removed{_SPREAD[args.speaker_norm]}",
                validation=False)
    test = ids[1]
    who = haskins_speaker(raw.utterance(test))
    r = _run("Haskins raw", raw, args.seed, test_ids=[test], inverse_table=False)
    r.notes.append("no speaker normalisation: the figures are dominated by the offset between the speakers' "
                   f"mean frames ({_offset(raw):.3g} mm RMS per coordinate); compare the mean-frame row")
    sec.add(f"Haskins, test {who} (raw)", r,
            f"Haskins pair, cross-speaker without normalisation: test speaker {who}", validation=False)
    return sec


def faces_corpus(faces_dir, store, mode="mean"):
    """The five clips, each imported with ``lipspace import`` at 60 Hz (once; kept in ``store``), pooled and
    normalised per speaker (``mode``: "mean" or "mean+scale")."""
    from dataclasses import replace

    from app.cli.evaluate import normalise_per_speaker
    from engine.io import concat
    from engine.recordings.corpus import Corpus
    from engine.recordings.kinematics import kinematic_if_unlabelled

    clips = sorted(Path(faces_dir).glob("*.mp4"))
    if not clips:
        return None, []
    store.mkdir(parents=True, exist_ok=True)
    parts, log = [], []
    for clip in clips:
        out = store / f"{clip.stem}.npz"
        if not out.exists():
            cmd = [sys.executable, "-m", "app.cli", "import", str(clip), "-o", str(out), "--resample", "60", "-q"]
            res = subprocess.run(cmd, cwd=str(REPO), capture_output=True, text=True)
            if res.returncode != 0:
                raise SystemExit(f"lipspace import {clip.name} failed:\n{res.stderr[-2000:]}")
        c = Corpus.load(out)
        parts.append(replace(c, utterances=[replace(u, speaker=clip.stem) for u in c.utterances]))
        log.append(f"{clip.name}: {c.n_frames} frames at {c.rate:g} Hz")
    pooled = concat(parts, name="talking-faces")
    labelled, note = kinematic_if_unlabelled(pooled)
    return normalise_per_speaker(labelled, mode=mode), log + ([note] if note else [])


def run_faces(args):
    from engine.evaluation.protocol_report import ProtocolResult

    sec = Section("faces")
    corpus, log = faces_corpus(args.faces_dir, Path(args.results_cache) / "faces", args.speaker_norm)
    if corpus is None:
        sec.markdown.append(f"### Talking faces\n\nNot run: no clips (*.mp4) in {Path(args.faces_dir).name}/.\n")
        return sec
    folds = [_run(f"faces, test {u.id}", corpus, args.seed, test_ids=[u.id], inverse_table=False, phones=False)
             for u in corpus.utterances]
    r = ProtocolResult.merge(folds, n_boot=2000, random_state=args.seed, notes=[
        "five real clips (one speaker each), imported with lipspace import (60 Hz) and pooled; each clip's mean "
        f"frame removed{_SPREAD[args.speaker_norm]} (engine.recordings.registration.normalise_speakers); targets: "
        "kinematic key frames (aperture maxima / minima, peak opening / closing velocities); leave one clip out: "
        "five folds, each fitted and validated on the other four clips only; the settings shown are the first "
        "fold's", *log])
    sec.add("Talking faces, 5 clips (leave one out)", r, "Talking faces: five real clips pooled, leave one clip out",
            validation=False)
    return sec


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(REPO / "docs" / "RESULTS.md"))
    ap.add_argument("--preset", default="default", choices=("small", "default"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--corpus", nargs="+", choices=CORPORA, default=None,
                    help="recompute only these corpora (the others from the results cache)")
    ap.add_argument("--haskins-dir", default=str(DEFAULT_HASKINS))
    ap.add_argument("--faces-dir", default=str(DEFAULT_FACES))
    ap.add_argument("--cache-dir", default=None, help="synthetic talker cache")
    ap.add_argument("--results-cache", default=None, help="per-corpus sections (default: <cache>/make-results)")
    ap.add_argument("--speaker-norm", default="mean", choices=tuple(_SPREAD),
                    help="per-speaker normalisation of the real corpora (default: %(default)s)")
    args = ap.parse_args()
    if args.results_cache is None:
        from engine.files.userdirs import user_dir

        args.results_cache = str(user_dir("cache", "LIPSPACE_CACHE_DIR") / "make-results")

    from engine.files.atomic import atomic_write

    t_all = time.perf_counter()
    commit, code = _commit(), _code_key()  # the code this run imports (taken before anything is computed)
    print(f"BLAS: {_blas()}", flush=True)
    store = Path(args.results_cache)
    store.mkdir(parents=True, exist_ok=True)
    todo = list(args.corpus or CORPORA)
    sections = {}
    for key in CORPORA:
        spread = "-" + args.speaker_norm if key in ("haskins", "faces") and args.speaker_norm != "mean" else ""
        path = store / f"{key}-{args.preset}-seed{args.seed}{spread}.json"
        cached = json.loads(path.read_text(encoding="utf-8")) if key not in todo and path.exists() else None
        if cached is not None and cached.get("format") == SECTION_FORMAT:
            sections[key] = cached
            stale = "" if cached["code"] == code else " (computed by other code)"
            print(f"{key}: from the results cache, commit {cached['commit']}{stale}", flush=True)
            continue
        print(f"{key}:", flush=True)
        t = time.perf_counter()
        sec = (run_synthetic(key, args) if key in ("default", "held-out") else
               run_haskins(args) if key == "haskins" else run_faces(args))
        sec.seconds = time.perf_counter() - t
        sections[key] = sec.as_dict(commit, code)
        with atomic_write(path) as tmp:
            Path(tmp).write_text(json.dumps(sections[key]), encoding="utf-8")
    total = time.perf_counter() - t_all
    text = _document(sections, commit, code, total)
    with atomic_write(args.out) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    print(f"wrote {args.out} in {total:.0f} s; max RSS {peak_rss_mb():.0f} MiB")


def _document(sections, commit, code, total):
    secs = [sections[k] for k in CORPORA if k in sections]
    summary = [e for s in secs for e in s["summary"]]
    lve = [e for s in secs for e in s["lve"]]
    contrib = [e for s in secs for e in s["contribution"]]
    stale = [f"`{s['key']}` (commit {s['commit']})" for s in secs if s["code"] != code]
    commits = sorted({s["commit"] for s in secs})
    best_rows = []
    for s in secs:
        for name, folds in s["best"]:
            cells = []
            for p in PROTOCOLS:
                picks = [f.get(p) for f in folds if f.get(p)]
                cells.append(", ".join(f"{m} ({picks.count(m)}/{len(folds)} folds)" for m in dict.fromkeys(picks))
                             if len(folds) > 1 and picks else (picks[0] if picks else "—"))
            best_rows.append(f"| {name} | " + " | ".join(cells) + " |")
    head = [
        "# Results: held-out synthesis under equal information",
        "",
        f"Generated by `tools/make_results.py` from commit{'s' * (len(commits) > 1)} "
        f"{', '.join(f'`{c}`' for c in commits)} on {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC "
        f"({platform.machine()}, Python {platform.python_version()}); sections computed in "
        + "; ".join(f"{s['key']} {s['seconds']:.0f} s" for s in secs)
        + f" (this run {total:.0f} s). Regenerate with `.venv/bin/python tools/make_results.py` "
          "(`--corpus NAME` recomputes one corpus). Do not edit by hand.",
        "",
    ]
    if stale:
        head += [f"**Stale sections** (computed by other code than the rest): {', '.join(stale)}.", ""]
    head += [
        "## Summary",
        "",
        "Who wins, per corpus and protocol, on RMSE X (the shape space, corpus units: mm). A cell names the "
        "method with the lowest pooled error and the margin Δ = manifold − other (negative: `manifold` erred "
        "less), against the runner-up when `manifold` wins and against the winner otherwise: the mean "
        "per-utterance difference with its 95 % bootstrap interval, the relative difference of the pooled "
        "errors, the utterances the winner wins, and the sign-test / signed-rank p-values. A corpus with one "
        "test utterance (each Haskins direction) pairs the gaps between its targets instead: interval, wins and "
        "tests over those gaps, which are parts of one sentence, not independent utterances.",
        "",
        *summary_table(summary, PROTOCOLS, "RMSE X"),
        "",
        "The same on the lip-vertex error (LVE, mm):",
        "",
        *summary_table(lve, PROTOCOLS, "LVE"),
        "",
        "What the manifold contributes in the `states` and `oracle` protocols, in two steps (RMSE X; Δ = the "
        "first method − the second, mean per utterance with its 95 % interval, negative: the first erred less; "
        "utterances the first wins): "
        "the states' mean velocities (the manifold's dynamic features) make the state-velocity Hermite spline "
        "beat interpolation without dynamics, and the learnt paths between the states make `manifold` beat "
        "the spline.",
        "",
        *contribution_table(contrib),
        "",
        "The synthesis method the explorer and `lipspace synthesize` use by default on each corpus: the one "
        "with the lowest RMSE X on the validation split of the training utterances (per protocol; for the "
        "folds of the talking faces, how many folds chose it).",
        "",
        "| corpus | `states` | `oracle` | `phones` |",
        "|---|---|---|---|",
        *best_rows,
        "",
        "## How to read the tables",
        "",
        "docs/METHOD.md gives the method and every decision.",
        "",
        "- **Protocol `states`**: every method gets only the target states (the state of each target frame's "
        "out-of-sample F^y). `manifold`: the state-velocity Hermite spline plus, per shape component, the "
        "validated share of the mean training path between the two states (the training sub-trajectories that "
        "leave one state's neighbourhood and reach the other's in about the gap's duration). `viterbi`: the "
        "paper's maximum-probability state path of exactly each gap's length, X from each state's mean F^x, "
        "smoothed. `sv-hermite`: state-velocity Hermite, the cubic Hermite spline through the states' mean X "
        "with the states' mean velocities. `pchip`, `linear`: through the states' mean X, no dynamics.",
        "- **Protocol `oracle`**: every method gets the true X at the targets and the target states; every "
        "trajectory passes through the true X.",
        "- **Protocol `phones`**: every method gets only the phones and their times (what `lipspace synthesize "
        "--text` has). `manifold`, `viterbi`: as above between the states the manifold's phone lattice "
        "chooses. `unitselection`: concatenative unit selection. `dominance`: Cohen–Massaro dominance "
        "functions (targets and dominance fitted). `sliding-window`: ridge regression from a window of phone "
        "labels to a window of shapes, overlap-averaged. `linear`: each phone's mean X at its mid-point. Not "
        "run on corpora without phone labels.",
        "- **`mean-frame`**: the training corpus's mean frame, held throughout.",
        "- **RMSE X**: RMS over frames of the Euclidean error in the shape space X. **RMSE Y3**: the same in "
        "the first 3 dims of Y, every trajectory projected through the same fitted pipeline. **LVE**: per frame "
        "the largest per-point error (mm), averaged. **vel. error**: RMSE of the velocity F^x' (first difference "
        "per frame) against the real one. **smoothness**: RMS second difference of the trajectory over that of "
        "the real lips (1: as rough as the capture, which includes its noise; lower: smoother), so a method "
        "cannot win by oversmoothing unseen. Scored from the first to the last target.",
        "- **ΔX vs manifold**: mean over utterances of (method's RMSE X − manifold's), 95 % bootstrap interval; "
        "positive: the manifold erred less. **manifold wins X / LVE**: utterances on which the manifold's error "
        "is lower. **p**: two-sided sign test and Wilcoxon signed-rank test.",
        "- Each table's verdict lines name every method that beats the manifold.",
        "",
        f"BLAS: {_blas()}.",
        "",
    ]
    body = [m for s in secs for m in s["markdown"] if m]
    return "\n".join(head) + "\n" + "\n".join(body) + "\n"


def _offset(corpus):
    """RMS per coordinate of the difference between the first two speakers' mean frames."""
    import numpy as np

    spk = np.array([u.speaker for u in corpus.utterances])[corpus.utterance_index]
    a, b = corpus.speakers[:2]
    d = corpus.frames[spk == a].mean(axis=0, dtype=np.float64) - corpus.frames[spk == b].mean(axis=0, dtype=np.float64)
    return float(np.sqrt(np.mean(d ** 2)))


def _validation_table(r) -> str:
    s = r.settings
    v = s.get("validation", {})
    if not v:
        return ""
    out = ["#### Validation (training utterances only)", "",
           "RMSE X of the manifold method (its weights fitted on the validation utterances) and of the "
           "state-velocity Hermite spline through the same states, per candidate state space:", "",
           "| state dims | frames per state | K | `states` manifold | `states` sv-hermite | `oracle` manifold | "
           "`oracle` sv-hermite |", "|---|---|---|---|---|---|---|"]
    for t in v.values():
        x = t["rmse_x"]
        out.append(f"| {t['dims']} | {t['frames_per_state']} | {t['K']} | {x['states/manifold']:.3f} | "
                   f"{x['states/sv-hermite']:.3f} | {x['oracle/manifold']:.3f} | {x['oracle/sv-hermite']:.3f} |")
    mv = s.get("method_validation") or {}
    if mv:
        methods = list(dict.fromkeys(m for r_ in mv.values() for m in r_))
        out += ["", "Every method at the chosen settings (validation RMSE X / LVE; the manifold method's weights "
                    "fitted on one half of the validation utterances and scored on the other, and vice versa):", "",
                "| protocol | " + " | ".join(f"`{m}`" for m in methods) + " |", "|---|" + "---|" * len(methods)]
        for p, r_ in mv.items():
            out.append(f"| `{p}` | " + " | ".join(f"{r_[m]['rmse_x']:.3f} / {r_[m]['lve']:.3f}" if m in r_ else ""
                                                   for m in methods) + " |")
    sw = s.get("sliding_window_errors")
    chosen = (f"Chosen: state dims {s['state_dims']}, one state per {s['frames_per_state']} frames, k "
              f"{s['n_neighbors']}, Viterbi smoothing " + ", ".join(f"{k} {x:g}" for k, x in s["sigma"].items()))
    if sw:
        chosen += "; sliding window (context/output/alpha) " + ", ".join(f"{k}: {e:.3f}" for k, e in sw.items())
    out += ["", chosen + f" ({s['note']}).", ""]
    return "\n".join(out)


if __name__ == "__main__":
    main()
