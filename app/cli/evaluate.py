"""``lipspace evaluate``: held-out synthesis under equal-information protocols.

Whole utterances are held out, the manifold is fitted on the rest, and each held-out
utterance is resynthesised by every method of the protocols of
:mod:`engine.evaluation.protocols` -- ``states`` (every method gets the target states),
``oracle`` (every method gets the oracle X at the targets and their states) and, for a
corpus with phone labels, ``phones`` (the phones and their times only) -- with the
mean-frame baseline, RMSE in X and in Y3 (the first three dimensions of the manifold
Y, every trajectory through the same out-of-sample projection), the lip-vertex error
(LVE), the velocity error and a smoothness figure, paired per-utterance statistics
against the manifold, and a verdict line per measure saying where the manifold loses.
``--state-dims``, the Viterbi smoothing and k are chosen on a validation split of the
training utterances unless given.

``--methods`` and ``--inverse-dims`` belonged to an older per-method table whose
methods did not get the same information; every one of its methods is scored by the
protocols, and the options now stop with an error that says where
(:data:`RETIRED_METHODS`).

Input: corpus files in any importable format (several are joined, one utterance
each), ``--haskins DIR`` (a folder of Haskins IEEE recordings), or nothing
(the synthetic talker, ``--preset``).
"""
from __future__ import annotations

from pathlib import Path

from app.cli.options import add_quiet_option, add_seed_option, add_talker_options

#: the older per-method table's methods -> where the protocols score them
RETIRED_METHODS = {
    "manifold": "oracle/viterbi and oracle/manifold",
    "linear": "oracle/linear",
    "cubic": "oracle/pchip",
    "unitselection": "phones/unitselection",
    "manifold-phones": "phones/viterbi and phones/manifold",
    "linear-phones": "phones/linear",
    "cubic-phones": "phones/linear (no cubic through the phones' means)",
}


def add_arguments(p):
    p.add_argument("corpus", nargs="*", metavar="CORPUS",
                   help="corpus file(s): native .npz or any importable format; omit for the synthetic talker")
    p.add_argument("--haskins", metavar="DIR", default=None,
                   help="evaluate on a folder of Haskins IEEE .mat recordings (every *.mat in DIR)")
    add_talker_options(p, default="small")
    p.add_argument("--test-fraction", type=float, default=0.1,
                   help="fraction of utterances held out, at least one (default: %(default)s)")
    p.add_argument("--test-ids", default=None, metavar="ID,ID,...", help="hold out exactly these utterances")
    p.add_argument("--methods", default=None, metavar="M,M,...",
                   help="retired (the older per-method table): its methods are rows of the protocols' table")
    p.add_argument("--states", type=int, default=None, help="K of the state graph (default: about N/30)")
    p.add_argument("--state-dims", type=int, default=None,
                   help="dims of Y clustered into states (default: chosen on a validation split of the "
                        "training utterances)")
    p.add_argument("--smoothing", type=float, default=None, metavar="FRAMES",
                   help="protocols: Gaussian smoothing of the Viterbi paths in frames (default: validated)")
    p.add_argument("--neighbors", type=int, default=None,
                   help="protocols: k of the local-linear inverse (default: validated)")
    p.add_argument("--speaker-norm", nargs="?", const="mean", default="auto",
                   choices=("auto", "mean", "mean+scale", "none"),
                   help="per-speaker normalisation: each speaker's mean frame removed first. auto (default, as "
                        "'lipspace build'): when the utterances name 2 or more speakers (with --haskins one speaker "
                        "per file, named by the file name's first field); mean (a bare --speaker-norm): always, "
                        "every utterance must name its speaker; mean+scale: always, and each speaker's spread "
                        "scaled to the pooled spread (as 'lipspace build --speaker-norm mean+scale'); none: never")
    p.add_argument("--inverse-dims", type=int, default=None,
                   help="retired with --methods: the protocols' table reports every inverse map")
    add_seed_option(p, what="the split and the manifold")
    p.add_argument("--csv", metavar="OUT.csv", default=None,
                   help="also write the table as CSV (protocols: protocol, method, utterance, rmse_x, rmse_y, "
                        "lve; one row per utterance and an ALL row per method)")
    p.add_argument("--markdown", metavar="OUT.md", default=None, help="protocols: also write the tables as Markdown")
    p.add_argument("--by", metavar="FIELD", default=None,
                   help="also report the errors per level of a metadata field of the utterances (speaker, sex, "
                        "emotion ...: lipspace info lists them); --csv then has a column FIELD and a "
                        "per-level table goes to FIELD-levels beside it")
    add_quiet_option(p)


def _corpus(args, progress):
    from app.cli import CliError
    from app.cli._common import load_corpus_arg

    if args.haskins and args.corpus:
        raise CliError("give corpus files or --haskins, not both")
    paths = sorted(Path(args.haskins).glob("*.mat")) if args.haskins else [Path(p) for p in args.corpus]
    if args.haskins and not paths:
        raise CliError(f"--haskins {args.haskins}: no Haskins recordings (*.mat) found in that folder")
    if not paths:
        return load_corpus_arg(None, synthetic_preset=args.preset, progress=progress)
    from engine.io import ImportFormatError, read_corpus
    from engine.recordings.kinematics import kinematic_if_unlabelled

    for p in paths:
        if not p.exists():
            raise CliError(f"{p}: no such file")
    try:
        corpus = read_corpus([str(p) for p in paths] if len(paths) > 1 else str(paths[0]))
        corpus, note = kinematic_if_unlabelled(corpus)  # no phones: targets at kinematic landmarks
    except (ImportFormatError, ValueError) as exc:
        raise CliError(str(exc)) from None
    if note:
        import sys

        print(f"lipspace evaluate: {note}", file=sys.stderr)
    return corpus


def run(args) -> int:
    if args.methods is not None or args.inverse_dims is not None:
        raise _retired(args)
    return _run_protocols(args)


def _retired(args):
    """The error for the retired per-method table's options: where the protocols score what they asked for."""
    from app.cli import CliError

    asked = [m.strip() for m in (args.methods or "").split(",") if m.strip()] or list(RETIRED_METHODS)
    where = "; ".join(f"{m} -> {RETIRED_METHODS.get(m, 'no such method')}" for m in asked)
    option = "--methods" if args.methods is not None else "--inverse-dims"
    return CliError(f"{option} belonged to the older per-method table, which is retired because its methods did not "
                    f"get the same information; run 'lipspace evaluate' without it: the protocols' table scores every "
                    f"method ({where}), the inverse maps in its own table, and --csv writes the per-utterance rows")


def haskins_speaker(utterance) -> str:
    """Speaker of a Haskins IEEE file: the first field of its name (``F01_B01_S01_R01_N`` -> ``F01``)."""
    return utterance.speaker or utterance.id.split("_")[0]


def name_haskins_speakers(corpus):
    """The corpus with every utterance's blank speaker named by :func:`haskins_speaker`."""
    from dataclasses import replace

    return replace(corpus, utterances=[replace(u, speaker=haskins_speaker(u)) for u in corpus.utterances])


def normalise_per_speaker(corpus, *, mode="mean"):
    """Each speaker's mean frame removed (:func:`engine.recordings.registration.normalise_speakers`).

    ``mode`` is ``"mean"`` or ``"mean+scale"`` (each speaker's spread also scaled to the pooled
    spread). Raises ValueError when an utterance names no speaker or for another mode.
    """
    from engine.recordings.registration import normalise_speakers

    if mode not in ("mean", "mean+scale"):
        raise ValueError(f"per-speaker normalisation {mode!r}; expected 'mean' or 'mean+scale'")
    blank = [u.id for u in corpus.utterances if not u.speaker]
    if blank:
        raise ValueError(f"{corpus.name}: utterance {blank[0]!r} names no speaker; per-speaker normalisation needs "
                         f"one per utterance (import with speakers, or use --haskins for the Haskins pair)")
    return normalise_speakers(corpus, mode=mode)


def _normalise_auto(corpus):
    """Per-speaker normalisation as ``lipspace build`` applies it by default (utterances naming no speaker are
    one group of their own)."""
    from engine.recordings.registration import normalise_speakers

    return normalise_speakers(corpus, mode="auto")


def _unseen_speakers(corpus, test_ids, args) -> dict:
    """Speakers of the held-out utterances that no training utterance has: ``{speaker: n test utterances}``.

    The split is the one the evaluation makes (:func:`engine.evaluation.protocols.split_utterances`, same seed).
    """
    from engine.evaluation.protocols import split_utterances

    train, test = split_utterances(corpus, test_fraction=args.test_fraction, test_ids=test_ids,
                                   random_state=args.seed)
    spk = {u.id: u.speaker for u in corpus.utterances}
    seen = {spk[i] for i in train}
    out: dict = {}
    for i in test:
        if spk[i] and spk[i] not in seen:
            out[spk[i]] = out.get(spk[i], 0) + 1
    out_all = sum(out.values()) == len(test)
    return {"unseen": out, "trained": sorted(s for s in seen if s), "all": out_all} if out else {}


def _unseen_text(corpus, unseen, normalised) -> str:
    """The warning for held-out speakers without training utterances; ``normalised``: the mode applied, or None."""
    who = ", ".join(f"{s} ({n} utterance{'s' * (n != 1)})" for s, n in unseen["unseen"].items())
    trained = ", ".join(unseen["trained"][:6]) or "unnamed speakers"
    disjoint = "train and test speakers are disjoint: " if unseen["all"] else ""
    done = "removes each speaker's mean frame" + (" and equalises their spreads" if normalised == "mean+scale" else "")
    tail = (f"per-speaker normalisation {done}, not how each one moves" if normalised else
            "without per-speaker normalisation the errors mostly measure the offset between the speakers' lips")
    return (f"{disjoint}the held-out speaker(s) {who} have no training utterance; the manifold is trained on "
            f"{trained} only and tested on lips it never saw ({tail}). For a within-speaker test hold out "
            "utterances of every speaker (--test-ids)")


def gap_cause(result, corpus, unseen) -> str:
    """The likely cause of the gaps whose state path could not reach its target in time, in words.

    In order: the training state graph falls apart (islands or strongly connected components, from
    the protocol's own state graph warnings and the training manifold's graph, with
    :func:`engine.recordings.registration.explain_split`'s reading of why), held-out speakers the training
    never saw, else targets more transitions apart than the frames between them allow.
    """
    from scipy.sparse.csgraph import connected_components

    from engine.recordings.registration import explain_split

    causes = []
    m = result.manifold
    if m is not None and getattr(m, "states_", None) is not None:
        st = m.states_
        n_weak, _ = connected_components(st.adjacency_, directed=True, connection="weak")
        K = st.centroids_.shape[0]
        if n_weak > 1 or st.n_scc_ > 1:
            parts = (f"{n_weak} islands with no transitions between them" if n_weak > 1 else
                     f"{st.n_scc_} strongly connected components (some states cannot be reached from others)")
            why = explain_split(st, m.corpus_)
            causes.append(f"the training state graph ({K} states) splits into {parts}"
                          + (f": {why}" if why else ""))
    if result.state_warnings and not causes:
        causes.append(f"the evaluation's state graph ({result.n_states} states) is not strongly connected "
                      "(see the state graph line)")
    if unseen:
        causes.append(f"held-out speaker(s) {', '.join(unseen['unseen'])} never appear in training, so their targets "
                      "fall on states the training speakers' transitions do not join")
    if not causes:
        causes.append("every target state is reachable, but some are more transitions apart than the frames "
                      "between the two targets (the path has exactly the gap's length)")
    return "likely cause: " + "; ".join(causes)


def _settings(args, manifold, progress):
    """Validated settings, overridden by whatever the command line fixes."""
    from engine.evaluation.protocols import PROTOCOLS, STATE_DIM_CANDIDATES, select_settings

    dims = (args.state_dims,) if args.state_dims is not None else STATE_DIM_CANDIDATES
    kw = {"state_dims": dims, "random_state": args.seed, "progress": progress, "n_states": args.states}
    if args.smoothing is not None:
        kw["sigmas"] = (float(args.smoothing),)
    if args.neighbors is not None:
        kw["neighbors"] = (int(args.neighbors),)
    s = select_settings(manifold, **kw)
    if len(s["validation"]) == 0:  # too few utterances to validate: the command line's values win
        if args.smoothing is not None:
            s["sigma"] = {f"{p}/viterbi": float(args.smoothing) for p in PROTOCOLS}
        if args.neighbors is not None:
            s["n_neighbors"] = int(args.neighbors)
    return s


def _run_protocols(args) -> int:
    import math

    from app.cli import CliError
    from app.cli._common import progress_bar
    from app.cli.synthesis_steps import MAX_SMOOTHING_FRAMES
    from engine.evaluation.protocols import evaluate_protocols
    from engine.manifold.model import Manifold

    for name in ("smoothing", "neighbors", "state_dims", "states"):
        v = getattr(args, name)
        if v is not None and not (v >= (0 if name == "smoothing" else 1) and math.isfinite(v)):
            raise CliError(f"--{name.replace('_', '-')} must be {'>= 0' if name == 'smoothing' else '>= 1'}, got {v}")
    if args.smoothing is not None and args.smoothing > MAX_SMOOTHING_FRAMES:
        raise CliError(f"--smoothing {args.smoothing:g}: at most {MAX_SMOOTHING_FRAMES:g} frames")
    test_ids = [s.strip() for s in args.test_ids.split(",") if s.strip()] if args.test_ids else None
    with progress_bar(disable=True if args.quiet else None) as progress:
        corpus = _corpus(args, progress)
        levels = _levels(args, corpus)  # --by: the field must exist before the work
        notes = []
        if args.haskins:
            corpus = name_haskins_speakers(corpus)
        spoken = [s for s in corpus.speakers if s]
        explicit = args.speaker_norm in ("mean", "mean+scale")
        normalise = explicit or (args.speaker_norm == "auto" and len(corpus.speakers) >= 2)
        mode = args.speaker_norm if explicit else "mean"  # what auto does with two or more speakers
        spread = " and its spread scaled to the pooled spread" if mode == "mean+scale" else ""
        if normalise:
            try:
                corpus = normalise_per_speaker(corpus, mode=mode) if explicit else \
                    _normalise_auto(corpus)
            except ValueError as exc:
                raise CliError(str(exc)) from None
            how = f"--speaker-norm {mode}" if explicit else "as 'lipspace build' does"
            notes.append(f"per-speaker normalisation: each speaker's mean frame removed{spread} "
                         f"({', '.join(s or '(unnamed)' for s in corpus.speakers)}; {how})")
        elif len(spoken) >= 2:
            notes.append(f"no per-speaker normalisation (--speaker-norm none) over {len(spoken)} speakers")
        try:
            unseen = _unseen_speakers(corpus, test_ids, args)
        except ValueError as exc:
            raise CliError(str(exc)) from None
        if unseen:
            import warnings

            from engine.recordings.corpus import CorpusWarning

            msg = _unseen_text(corpus, unseen, mode if normalise else None)
            warnings.warn(CorpusWarning(msg), stacklevel=2)
            notes.append(f"warning: {msg}")
        speaker_norm = "none" if args.speaker_norm == "none" else "auto"

        def factory(train):
            return Manifold(n_states=args.states, random_state=args.seed,
                            speaker_normalisation=speaker_norm).fit(train, progress=progress)

        try:
            result = evaluate_protocols(
                corpus, manifold_factory=factory, test_fraction=args.test_fraction, test_ids=test_ids,
                random_state=args.seed, progress=progress,
                settings_factory=lambda m: _settings(args, m, progress))
        except ValueError as exc:
            from app.cli.argtypes import plain_words

            raise CliError(plain_words(str(exc))) from None
        result.notes.extend(notes)
        if result.missed_gaps:
            import warnings

            from engine.recordings.corpus import CorpusWarning

            cause = gap_cause(result, corpus, unseen)
            result.notes.append(f"unreachable gaps: {cause}")
            warnings.warn(CorpusWarning(f"{result.missed_gaps} gap(s) could not reach their target state in time "
                                        f"(they end at the nearest reachable state); {cause}"), stacklevel=2)
    print(result.format())
    level_rows = _print_levels(args, result, levels)
    from app.cli._common import command_outputs

    with command_outputs(args) as outputs:  # both tables or neither
        if args.csv:
            from engine.evaluation.protocol_report import CSV_COLUMNS
            from engine.io.writers.export import write_table_csv

            rows, cols = result.csv_rows(), list(CSV_COLUMNS)
            if levels is not None:  # the utterance's level beside it (ALL rows: none)
                rows = [{**r, args.by: levels.get(r["utterance"], "")} for r in rows]
                cols.insert(cols.index("utterance") + 1, args.by)
                from engine.evaluation.levels import LEVEL_COLUMNS

                write_table_csv(outputs.file(_levels_csv(args.csv), option="--csv"), level_rows,
                                columns=LEVEL_COLUMNS)
            write_table_csv(outputs.file(args.csv, option="--csv"), rows, columns=cols)
        if args.markdown:
            outputs.file(args.markdown, option="--markdown").write_text(result.markdown() + "\n", encoding="utf-8")
    if args.csv and levels is not None:
        print(f"wrote {_levels_csv(args.csv)}")
    for written in (args.csv, args.markdown):
        if written:
            print(f"wrote {written}")
    if sum(int(r.get("utterances") or 0) for r in result.rows) == 0:
        import sys

        print("lipspace evaluate: every item failed: no method synthesised any held-out utterance under any "
              "protocol", file=sys.stderr)
        return 1
    return 0


def _levels(args, corpus):
    """``{utterance id: level}`` of ``--by FIELD`` (None without it); CliError naming the fields the corpus has."""
    if not args.by:
        return None
    from app.cli import CliError
    from engine.recordings.metadata import MetadataError, field_values, require_field

    try:
        require_field(corpus, args.by)
    except MetadataError as exc:
        raise CliError(f"--by {args.by}: {exc}") from None
    return dict(zip((u.id for u in corpus.utterances), field_values(corpus, args.by).tolist()))


def _print_levels(args, result, levels):
    """Print the per-level table of ``--by``; its rows (None without ``--by``)."""
    if levels is None:
        return None
    from engine.evaluation.levels import format_levels, per_level

    rows = per_level(result, levels, field=args.by)
    print()
    print(format_levels(rows, field=args.by))
    return rows


def _levels_csv(path) -> Path:
    """Where ``--csv OUT.csv`` puts the per-level table: ``OUT-levels.csv``."""
    p = Path(path)
    return p.with_name(f"{p.stem}-levels{p.suffix or '.csv'}")
