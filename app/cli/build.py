"""``lipspace build``: corpus (or the synthetic talker) -> manifold file."""
from __future__ import annotations

import sys
import time
from pathlib import Path

from app.cli._common import load_corpus_arg, progress_bar
from app.cli.options import add_manifold_options, add_quiet_option, add_talker_options, manifold_params
from app.files.source_loading import ANALYSIS_RATE


def add_arguments(p):
    p.add_argument("corpus", nargs="?", help="native corpus file (.npz, frames inside or in blocks beside it: "
                                             "'lipspace import --block-frames'; a manifold built from blocks reads "
                                             "its frames from them, so keep the corpus); omit for the synthetic "
                                             "talker")
    add_talker_options(p, kinematics="moves the jaw, upper lip and corners as real speakers' articulograph "
                                     "sensors do (opt-in)")
    p.add_argument("-o", "--output", required=True, help="manifold file to write (.npz)")
    add_manifold_options(p)
    p.add_argument("--dask", metavar="local|ADDRESS", default=None,
                   help="run the shape space and the embedding on Dask: 'local' starts a cluster with one worker "
                        "per core, an address (tcp://host:8786) uses a running scheduler (default: in-process)")
    p.add_argument("--dask-blocks", metavar="DIR", default=None,
                   help="folder for the frames stored in blocks, readable by every worker (default: a temporary "
                        "folder; give shared storage for workers on other machines)")
    p.add_argument("--no-method-choice", dest="method_choice", action="store_false",
                   help="leave out measuring which synthesis method is best on the corpus's own validation split "
                        "(by default the build measures it and stores it in the file, so the first synthesis "
                        "starts at once; without it the first synthesis measures it)")
    add_quiet_option(p)


def run(args) -> int:
    from app.cli._common import command_outputs

    with command_outputs(args) as outputs:  # reserved now; at the end no file that appeared meanwhile is replaced
        said = _fit_and_save(args, outputs)
    print(said, file=sys.stdout)
    return 0


def _fit_and_save(args, outputs) -> str:
    """Fit the manifold and save it to its staged output; returns the line to print once it is in place."""
    from app.cli import CliError
    from engine.manifold.model import Manifold

    out = Path(args.output)
    if out.suffix != ".npz":
        raise CliError(f"{out}: the manifold file must end in .npz")
    staged = outputs.file(out, option="-o")
    t0 = time.perf_counter()
    with progress_bar(disable=True if args.quiet else None) as progress:
        if args.corpus is not None and args.kinematics != "classic":
            raise CliError("--kinematics chooses the synthetic talker's; it does nothing with a corpus file "
                           f"({args.corpus}): leave it out")
        # a corpus stored in blocks ('lipspace import --block-frames') keeps its frames in the block files
        corpus = load_corpus_arg(args.corpus, synthetic_preset=args.preset, progress=progress,
                                 kinematics=args.kinematics, audio=True)
        if abs(corpus.rate - ANALYSIS_RATE) > 3.0:  # docs/USER_GUIDE.md, "Real recordings"
            print(f"lipspace build: warning: {corpus.name} is at {corpus.rate:g} Hz; the method's analysis rate is "
                  "60 Hz (the paper's): velocities, classes and states differ at other rates. Resample with "
                  "'lipspace import CORPUS --resample 60 -o OUT.npz'", file=sys.stderr)
        _check_sizes(args, corpus)
        try:
            from engine.manifold.buildplan import plan_build

            plan = plan_build(corpus.n_frames, n_landmarks=args.landmarks, landmarks_above=args.landmarks_above)
            print(f"lipspace build: {plan.describe()}", file=sys.stdout)
            executor = _dask_executor(args)
            manifold = Manifold(**manifold_params(args))
            try:
                manifold.fit(corpus, progress=progress, executor=executor, plan=plan)
            finally:
                if executor is not None:
                    executor.close()
            if args.method_choice:
                # the synthesis methods measured on the corpus's validation split, stored in the file
                from engine.synthesis.method_choice import fit_choice

                fit_choice(manifold, progress=progress)
        except ValueError as exc:
            from app.cli.argtypes import plain_words

            raise CliError(plain_words(str(exc))) from None
    manifold.save(staged)
    s = manifold.summary()
    said = (f"wrote {out}: {s['frames']} frames, {s['shape_components']} shape components, "
            f"Y {s['embedding_dims']}-D (first 3 hold {100 * s['Y_first3_recovered']:.1f}% of recovered variance), "
            f"K={s['n_states']} states, {time.perf_counter() - t0:.1f} s")
    if manifold.synthesis_choice_ is not None:
        best = manifold.synthesis_choice_.get("best") or {}
        said += "\nsynthesis: best on validation " + (", ".join(f"{p} {m}" for p, m in best.items()) or
                                                       f"not measured ({manifold.synthesis_choice_.get('note')})")
    return said


def _check_sizes(args, corpus) -> None:
    """Refuse options the corpus is too small for, naming the option (not the corpus) as the cause."""
    from app.cli import CliError

    n = corpus.n_frames
    if args.states is not None and args.states > n:
        raise CliError(f"--states {args.states}: more states than {corpus.name} has frames ({n}); give at most {n}, "
                       "or leave the option out (about one state per 30 frames)")
    if args.embedding_dims + 2 > n >= 12:
        raise CliError(f"--embedding-dims {args.embedding_dims}: {corpus.name} has {n} frames, enough for at most "
                       f"{n - 2} dimensions; give fewer (the paper uses 16)")
    if args.landmarks is not None and args.landmarks > n:
        raise CliError(f"--landmarks {args.landmarks}: more landmarks than {corpus.name} has frames ({n})")


def _dask_executor(args):
    """The Dask executor named by ``--dask`` (None: in-process), its cluster printed."""
    if not args.dask:
        return None
    try:
        from engine.scale.executor import DaskExecutor
    except ImportError as exc:
        from app.cli import CliError

        raise CliError(f"--dask needs the 'scale' extra ({exc}); "
                       "install it with pip install 'lipspace[scale]'") from None
    ex = DaskExecutor.connect(args.dask, chunk_dir=args.dask_blocks)
    print(f"lipspace build: Dask {ex.describe()}", file=sys.stdout)
    return ex
