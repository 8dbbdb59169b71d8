"""Calibration of ``lipspace compare`` on the synthetic talker: false positives over random splits, and known
differences found where they are and not elsewhere.

Two parts, each on corpora of :mod:`engine.talker.conditions` (small preset, 60 Hz):

* **random splits of one condition**: every utterance spoken the same way; the utterances are split at random
  into two "levels" many times, each split compared as ``lipspace compare`` would (one manifold, whole-utterance
  resampling), in three designs -- free (one speaker), paired by text, within speaker (three speakers) -- and,
  as the baseline a frame-level analysis would be, with every frame (or cluster member) its own unit. Per
  family: the share of splits with any row at q < 0.05 (under no difference at all Benjamini-Hochberg keeps
  this at or below 0.05), and the share of all rows with p < 0.05 (nominal 0.05);
* **known differences**: the conditions of the tests (10 sentences x 2 repetitions, paired by text) with wider
  bilabial releases or slower closing, at the default size and at half of it, over several seeds: whether the
  cluster that differs most is a bilabial, whether the speed measure the effect acts on passes, and how many
  passing cluster rows fall on clusters the effect never touched.

``--write`` replaces the generated section of ``docs/BENCHMARKS.md``. Prints wall time per comparison, peak
memory and the BLAS kernel.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from _common import blas_kernel, peak_rss_mb  # noqa: E402

DOC = Path(__file__).resolve().parents[1] / "docs" / "BENCHMARKS.md"
BEGIN, END = "<!-- calibrate_comparison: begin -->", "<!-- calibrate_comparison: end -->"
FAMILIES = ("cluster", "dynamics", "state")


def _interval(k, n):
    from scipy.stats import binomtest

    if n == 0:
        return "-"
    ci = binomtest(int(k), int(n)).proportion_ci(0.95)
    return f"{k / n:.3f} [{ci.low:.3f}, {ci.high:.3f}]"


def _fit(conditions, **kw):
    from engine.manifold.model import Manifold
    from engine.talker.conditions import condition_corpus

    cc = condition_corpus(conditions=conditions, preset="small", **kw)
    return cc, Manifold().fit(cc.corpus)


def _split(rng, groups, n):
    """Per utterance (n) "x" / "y": each group of utterance indices split in half at random ("" outside them)."""
    out = np.full(n, "", dtype=object)
    for idx in groups:
        perm = rng.permutation(np.asarray(idx))
        out[perm[: len(perm) // 2]], out[perm[len(perm) // 2:]] = "x", "y"
    return out


def _tally(store, result):
    s = store.setdefault("all three", {"splits": 0, "any": 0, "p05": 0, "tests": 0})
    s["splits"] += 1
    s["any"] += int(any(r["q"] < 0.05 for r in result.rows_))
    s["p05"] += int(sum(r["p"] < 0.05 for r in result.rows_))
    s["tests"] += int(sum(np.isfinite(r["p"]) for r in result.rows_))
    for fam in FAMILIES:
        rows = result.table(family=fam)
        p = np.array([r["p"] for r in rows], float)
        q = np.array([r["q"] for r in rows], float)
        s = store.setdefault(fam, {"splits": 0, "any": 0, "p05": 0, "tests": 0})
        s["splits"] += 1
        s["any"] += int(np.any(q < 0.05))
        s["p05"] += int(np.sum(p < 0.05))
        s["tests"] += int(np.sum(np.isfinite(p)))


def _naive(m, levels, n_permutations, seed):
    """The split tested with every frame its own unit (cluster members for the clusters): results per family."""
    from engine.comparison.cluster_shift import cluster_family
    from engine.comparison.design import resolve_design
    from engine.comparison.dynamics import dynamics_family, utterance_dynamics
    from engine.comparison.enrichment import enrichment_family, state_counts
    from engine.comparison.statistics import bh_qvalues, run_families
    from engine.manifold.clusters import clusters_of

    c = m.corpus_
    N = c.n_frames
    frame_levels = np.asarray(levels, dtype=str)[c.utterance_index]
    d = resolve_design(frame_levels, "x", "y", by="split")
    frames = np.arange(N)
    pc, _, _ = clusters_of(m)
    dyn = utterance_dynamics(m, unit_index=frames)
    fams = [dynamics_family(dyn, d.utterances), enrichment_family(state_counts(m.states_.labels_, frames, N,
                                                                              m.states_.centroids_.shape[0]),
                                                                 d.utterances),
            cluster_family(pc, m.Fy_, frames, d.utterances, space="Y", n_dims=3),
            cluster_family(pc, m.Fx_, frames, d.utterances, space="X", n_dims=3, scale=1 / np.sqrt(c.n_points))]
    res = run_families(d, fams, n_permutations=n_permutations, n_bootstrap=0, random_state=seed)
    M, K, C = dyn.numerator.shape[1], m.states_.centroids_.shape[0], len(pc.phones_)
    p = {"dynamics": res[0].p[:M], "state": res[1].p[:K], "cluster": np.r_[res[2].p[:2 * C], res[3].p[:2 * C]]}
    return {f: (p[f], bh_qvalues(p[f])) for f in FAMILIES}


def null_calibration(args, out):
    from engine.comparison.compare import ConditionComparison

    same = {"a": "none", "b": "none"}
    t0 = time.perf_counter()
    cc1, m1 = _fit(same, n_texts=15, repetitions=2, seed=101)
    cc3, m3 = _fit(same, n_texts=6, repetitions=2, speakers=3, seed=202)
    out.append(f"The two split corpora ({m1.corpus_.n_frames} and {m3.corpus_.n_frames} frames) were generated and "
               f"fitted in {time.perf_counter() - t0:.0f} s.")
    rng = np.random.default_rng(args.seed)
    tallies = {k: {} for k in ("free", "paired", "speaker", "naive")}
    times = []
    n1 = len(cc1.corpus.utterances)
    texts, spk = cc1.fields["text"], cc3.fields["speaker"]
    blocks = [np.flatnonzero(texts == t) for t in np.unique(texts)]
    speakers = [np.flatnonzero(spk == s) for s in np.unique(spk)]
    cmp = ConditionComparison(n_permutations=args.permutations, n_bootstrap=0)
    for k in range(args.splits):
        free = _split(rng, [np.arange(n1)], n1)
        t = time.perf_counter()
        _tally(tallies["free"], cmp.set_params(random_state=k).fit(m1, free, by="split", contrasts=[("x", "y")],
                                                                   speakers=cc1.fields["speaker"]))
        times.append(time.perf_counter() - t)
        _tally(tallies["paired"], cmp.fit(m1, _split(rng, blocks, n1), by="split", contrasts=[("x", "y")],
                                          speakers=cc1.fields["speaker"], pairs=texts, paired_by="text"))
        _tally(tallies["speaker"], cmp.fit(m3, _split(rng, speakers, len(spk)), by="split", contrasts=[("x", "y")],
                                           speakers=spk))
        if k < args.naive_splits:
            for fam, (p, q) in _naive(m1, free, args.permutations, k).items():
                s = tallies["naive"].setdefault(fam, {"splits": 0, "any": 0, "p05": 0, "tests": 0})
                s["splits"] += 1
                s["any"] += int(np.any(q < 0.05))
                s["p05"] += int(np.sum(p < 0.05))
                s["tests"] += int(np.sum(np.isfinite(p)))
        if (k + 1) % 10 == 0:
            print(f"  {k + 1}/{args.splits} splits", file=sys.stderr)
    return tallies, times


def detection(args, out):
    from engine.comparison.compare import ConditionComparison
    from engine.talker.conditions import DEFAULT_SIZE

    rows = []
    for scale in (1.0, 0.5):
        sizes = {e: DEFAULT_SIZE[e] * scale for e in ("bilabial_release", "slow_closing")}
        for seed in range(args.seeds):
            cc, m = _fit({"a": "none", "b": ("bilabial_release", sizes["bilabial_release"]),
                          "c": ("slow_closing", sizes["slow_closing"])}, n_texts=10, repetitions=2, seed=1000 + seed)
            c = m.corpus_
            v = np.gradient(c.latent["aperture"]) * c.rate
            cond = cc.fields["condition"][c.utterance_index]
            for level, effect, target in (("b", "bilabial_release", "while opening"),
                                          ("c", "slow_closing", "while closing")):
                r = ConditionComparison(n_permutations=args.permutations, n_bootstrap=0, random_state=seed).fit(
                    m, cc.fields["condition"], by="condition", contrasts=[("a", level)], pairs=cc.fields["text"],
                    paired_by="text")
                sel = v > 0 if target == "while opening" else v < 0
                truth = np.abs(v[(cond == level) & sel]).mean() / np.abs(v[(cond == "a") & sel]).mean()
                pc, uidx = r.clusters_, c.utterance_index
                touched = {}
                for i, ph in enumerate(pc.phones_):
                    mem = pc.members_[pc.member_offsets_[i]:pc.member_offsets_[i + 1]]
                    mine = cc.fields["condition"][uidx[mem]] == level
                    touched[ph] = bool(np.any(cc.effect_mm[mem][mine] > 0.1))
                clusters = sorted(r.table(family="cluster"), key=lambda x: x["p"])
                sig = [x for x in clusters if x["q"] < 0.05]
                dyn = next(x for x in r.table(family="dynamics") if x["target"] == target)
                moved = (cc.effect_mm > 0.1) & (cond == level)
                top = [int(x["target"]) for x in sorted(r.table(family="state"), key=lambda x: x["p"])[:10]]
                rows.append({"effect": effect, "size": sizes[effect], "seed": seed, "truth": truth,
                             "top_states": moved[np.isin(m.states_.labels_, top)].mean() / max(moved.mean(), 1e-12),
                             "top_bilabial": clusters[0]["target"] in ("p", "b"),
                             "speed_found": dyn["q"] < 0.05 and (dyn["estimate"] - 1) * (truth - 1) > 0,
                             "speed_estimate": dyn["estimate"], "sig_clusters": len(sig),
                             "sig_untouched": sum(not touched[x["target"]] for x in sig),
                             "sig_states": len(r.significant(family="state"))})
            print(f"  detection: size x{scale} seed {seed} done", file=sys.stderr)
    return rows


def _markdown(args, tallies, times, det, header) -> str:
    lines = [BEGIN, "", "## Comparing conditions: calibration", "",
             "Generated by `benchmarks/calibrate_comparison.py"
             + (f" --splits {args.splits} --seeds {args.seeds} --permutations {args.permutations}`"
                f" (seed {args.seed}); do not edit by hand."), "", *header, "",
             "**Random splits of one condition.** Utterances all spoken the same way, split at random into two",
             "levels; each split compared on one manifold. *any q < 0.05*: share of splits with at least one row",
             "of the family passing (Benjamini-Hochberg keeps it at or below 0.05 when nothing differs); *p < 0.05*:",
             "share of all rows (nominal 0.05). Brackets: 95 % Clopper-Pearson intervals; those of the rows treat",
             "the rows of one split as independent, which they are not, and are too narrow.", "",
             "| design | family | splits | any q < 0.05 | p < 0.05 (rows) |", "|---|---|---|---|---|"]
    names = {"free": "one speaker, utterances exchangeable (60 utterances)",
             "paired": "paired by text (15 sentences x 4 tokens)",
             "speaker": "within speaker (3 speakers x 24 utterances)",
             "naive": "baseline: frames as units (the free split)"}
    for key, name in names.items():
        for fam in (*FAMILIES, "all three"):
            s = tallies[key].get(fam)
            if s:
                lines.append(f"| {name} | {fam} | {s['splits']} | {_interval(s['any'], s['splits'])} | "
                             f"{_interval(s['p05'], s['tests'])} |")
    lines += ["", f"Wall time per comparison (free design, {args.permutations} permutations, no bootstrap): "
              f"min {min(times):.2f} s, median {np.median(times):.2f} s.", "",
              "**Known differences.** Three conditions of 10 sentences x 2 repetitions (paired by text): as spoken,",
              "wider bilabial releases, slower closing; each effect at its default size and at half of it, one",
              "corpus and manifold per seed. *truth*: the effect's speed ratio on the talker's true aperture",
              "(opening speed for the release, closing speed for slow closing); *top cluster bilabial*: the",
              "cluster row with the smallest p is /b/ or /p/; *speed found*: the measure the effect acts on has",
              "q < 0.05 in the true direction; *passing clusters (untouched)*: cluster rows at q < 0.05, and how",
              "many of them are clusters whose members the effect never moved; *top states*: the share of frames",
              "the effect moved among the frames of the ten states with the smallest p, over their share in the",
              "whole corpus (1 = no localisation).", "",
              "| effect | size | seeds | truth (mean) | top cluster bilabial | speed found | speed ratio (mean) "
              "| passing clusters (untouched) | passing states | top states (mean) |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for effect in ("bilabial_release", "slow_closing"):
        for size in sorted({r["size"] for r in det if r["effect"] == effect}, reverse=True):
            rs = [r for r in det if r["effect"] == effect and r["size"] == size]
            top = f"{sum(r['top_bilabial'] for r in rs)}/{len(rs)}" if effect == "bilabial_release" else "-"
            lines.append(f"| {effect} | {size:g} | {len(rs)} | {np.mean([r['truth'] for r in rs]):.3f} | {top} | "
                         f"{sum(r['speed_found'] for r in rs)}/{len(rs)} | "
                         f"{np.mean([r['speed_estimate'] for r in rs]):.3f} | "
                         f"{sum(r['sig_clusters'] for r in rs)} ({sum(r['sig_untouched'] for r in rs)}) | "
                         f"{sum(r['sig_states'] for r in rs)} | {np.mean([r['top_states'] for r in rs]):.1f} |")
    return "\n".join(lines + ["", END])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--splits", type=int, default=100, help="random splits per design (default: %(default)s)")
    ap.add_argument("--naive-splits", type=int, default=30, help="splits tested frame by frame (default: %(default)s)")
    ap.add_argument("--seeds", type=int, default=3, help="corpora per effect size (default: %(default)s)")
    ap.add_argument("--permutations", type=int, default=499, help="per comparison (default: %(default)s)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--write", action="store_true", help=f"replace the generated section of {DOC.name}")
    args = ap.parse_args(argv)
    os.environ.setdefault("LIPSPACE_CACHE_DIR", str(Path(__file__).resolve().parents[1] / ".cache"))
    t0 = time.perf_counter()
    load0 = os.getloadavg()[0]
    notes = []
    tallies, times = null_calibration(args, notes)
    det = detection(args, notes)
    wall = time.perf_counter() - t0
    header = [f"Taken in {wall / 60:.0f} min on the shared 2-core machine (load average {load0:.1f} at the start, "
              f"{os.getloadavg()[0]:.1f} at the end); peak memory {peak_rss_mb():.0f} MiB; BLAS: {blas_kernel()}.",
              *notes]
    text = _markdown(args, tallies, times, det, header)
    print(text)
    if args.write:
        doc = DOC.read_text(encoding="utf-8")
        if BEGIN in doc and END in doc:
            doc = doc[:doc.index(BEGIN)] + text + doc[doc.index(END) + len(END):]
        else:
            doc = doc.rstrip("\n") + "\n\n" + text + "\n"
        DOC.write_text(doc, encoding="utf-8")
        print(f"wrote {DOC}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
