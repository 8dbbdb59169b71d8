"""``lipspace evaluate``: held-out synthesis, every method, one table.

Whole utterances are held out, the manifold is fitted on the rest, and each held-out
utterance is resynthesised from its phones by every method and compared with the
real lips (RMSE in X, mean and max per-point error in the corpus's units,
correlation of the first three shape components, and RMSE Y3: the error in the first
three dimensions of the manifold Y, where the paper's Fig. 3 draws its trajectories --
the manifold method's state path before the inverse map, every X-space method's
trajectory projected out-of-sample, against the held-out utterance's own projection).

Input: corpus files in any importable format (several are joined, one utterance
each), ``--haskins`` (the two Haskins IEEE samples beside the project), or nothing
(the synthetic talker, ``--preset``).
"""
from __future__ import annotations

from pathlib import Path

PRESETS = ("small", "default", "paper")
HASKINS_DIR = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "haskins-ieee"


def add_arguments(p):
    from engine.evaluation import DEFAULT_METHODS, EVALUATION_METHODS

    p.add_argument("corpus", nargs="*", metavar="CORPUS",
                   help="corpus file(s): native .npz or any importable format; omit for the synthetic talker")
    p.add_argument("--haskins", action="store_true",
                   help=f"evaluate on the Haskins IEEE sample pair ({HASKINS_DIR})")
    p.add_argument("--preset", choices=PRESETS, default="small",
                   help="synthetic talker preset when no corpus is given (default: %(default)s)")
    p.add_argument("--test-fraction", type=float, default=0.1,
                   help="fraction of utterances held out, at least one (default: %(default)s)")
    p.add_argument("--test-ids", default=None, metavar="ID,ID,...", help="hold out exactly these utterances")
    p.add_argument("--methods", default=",".join(DEFAULT_METHODS), metavar="M,M,...",
                   help=f"comma-separated, from: {', '.join(EVALUATION_METHODS)} (default: %(default)s)")
    p.add_argument("--states", type=int, default=None, help="K of the state graph (default: about N/30)")
    p.add_argument("--state-dims", type=int, default=3, help="dims of Y clustered into states (default: 3)")
    p.add_argument("--inverse-dims", type=int, default=None,
                   help="manifold methods: dims of the Y -> X inverse map (default: the manifold's, 3)")
    p.add_argument("--seed", type=int, default=0, help="seed of the split and the manifold (default: 0)")
    p.add_argument("--csv", metavar="OUT.csv", default=None, help="also write the table as CSV")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")


def _corpus(args, progress):
    from app.cli import CliError
    from app.cli._common import load_corpus_arg

    if args.haskins and args.corpus:
        raise CliError("give corpus files or --haskins, not both")
    paths = sorted(HASKINS_DIR.glob("*.mat")) if args.haskins else [Path(p) for p in args.corpus]
    if args.haskins and not paths:
        raise CliError(f"no Haskins samples (*.mat) found in {HASKINS_DIR}")
    if not paths:
        return load_corpus_arg(None, synthetic_preset=args.preset, progress=progress)
    from engine.io import ImportFormatError, read_corpus

    for p in paths:
        if not p.exists():
            raise CliError(f"{p}: no such file")
    try:
        return read_corpus([str(p) for p in paths] if len(paths) > 1 else str(paths[0]))
    except (ImportFormatError, ValueError) as exc:
        raise CliError(str(exc)) from None


def run(args) -> int:
    from app.cli import CliError
    from app.cli._common import progress_bar
    from engine.evaluation import EVALUATION_METHODS, evaluate
    from engine.manifold import Manifold

    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    bad = [m for m in methods if m not in EVALUATION_METHODS]
    if bad or not methods:
        raise CliError(f"unknown method(s) {', '.join(bad) or '(none given)'}; choose from "
                       f"{', '.join(EVALUATION_METHODS)}")
    test_ids = [s.strip() for s in args.test_ids.split(",") if s.strip()] if args.test_ids else None
    with progress_bar(disable=True if args.quiet else None) as progress:
        corpus = _corpus(args, progress)

        def factory(train):
            return Manifold(n_states=args.states, state_dims=args.state_dims, random_state=args.seed).fit(
                train, progress=progress)

        try:
            result = evaluate(corpus, manifold_factory=factory, test_fraction=args.test_fraction, test_ids=test_ids,
                              methods=methods, random_state=args.seed, progress=progress,
                              synthesizer_params={"manifold": {"inverse_dims": args.inverse_dims}})
        except ValueError as exc:
            raise CliError(str(exc)) from None
    print(result.format())
    if args.csv:
        from engine.io.export import write_table_csv

        write_table_csv(args.csv, result.table())
        print(f"wrote {args.csv}")
    return 0
