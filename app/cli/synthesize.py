"""``lipspace synthesize``: phones, a TextGrid, text or a corpus utterance -> trajectory and mesh files.

The manifold comes from ``--manifold FILE`` (written by ``lipspace build``) or is
fitted on the synthetic talker (``--preset``). Targets:

================================  ==================================================================================
``--phones "p 0.08 ax 0.1 ..."``  labels and durations (s); any phone set the corpus's labels normalise to
``--textgrid FILE``               a Praat TextGrid (or HTK/MOCHA .lab) phone tier
``--text "..."``                  English text through the pronouncing dictionary and the duration model
``--utterance ID``                a corpus utterance's own phone mid-points (oracle targets, as the paper's Fig. 3);
                                  with ``--key-frames F,F,...`` or ``--key-frames kinematic`` its frames at those
                                  indices / at its kinematic landmarks (the default when it has no phones)
``--states S,S,...``              manifold states (e.g. clicked in the explorer), ``--spacing`` seconds apart
================================  ==================================================================================

``--method best`` (the default) takes the method measured best on the corpus's own
validation split for the kind of targets given (:mod:`engine.synthesis.method_choice`: measured
once per corpus and cached) and names it with its margin.

Outputs: ``-o traj.csv`` / ``-o traj.npy`` (``--values`` frames, fx or fy),
``-o speech.glb`` / ``.gltf`` (a glTF 2.0 morph-target animation: mean shape, shape
components as targets, F^x as weights; the utterance's or ``--audio`` sound as a WAV
beside it) and ``--mesh-dir DIR`` (one OBJ/PLY per frame), each written atomically.
``--praat OUT.TextGrid`` writes, for Praat, the synthesis on the input alignment's timeline
(:mod:`engine.synthesis.tiers`): a TextGrid with the input's span and phone tier, the
targets and the synthesised opening's kinematic landmarks, and ``OUT.csv`` (its units in
``OUT.csv.json``) with the synthesised aperture per frame.
"""
from __future__ import annotations

import sys
from pathlib import Path

from engine.synthesis.methods import SYNTHESIS_METHODS

PRESETS = ("small", "default", "paper")
#: the registry's methods (engine.synthesis.methods); "best" resolves to one of them
METHODS = tuple(SYNTHESIS_METHODS)
BEST = "best"
#: the manifold synthesiser's inverse maps (engine.synthesis.viterbi.INVERSES; a test keeps them equal)
INVERSES = ("delaunay", "state-mean", "local-linear")
VALUES = ("frames", "fx", "fy")


def _values_meaning(values: str, corpus) -> str:
    """What each row of a written trajectory holds, in words: ``"x, y, z of 156 points"``,
    ``"shape coordinates F^x"`` or ``"manifold coordinates F^y"`` (``--values``)."""
    if values == "frames":
        dim = corpus.frames.shape[1] // max(corpus.n_points, 1)
        return f"{', '.join('xyz'[:dim])} of {corpus.n_points} points"
    return "shape coordinates F^x" if values == "fx" else "manifold coordinates F^y"


def add_arguments(p):
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--phones", metavar='"P DUR ..."', help='phone labels with durations in seconds, e.g. "p 0.08 ax 0.1"')
    src.add_argument("--textgrid", metavar="FILE", help="Praat TextGrid (or .lab) phone alignment")
    src.add_argument("--text", metavar='"TEXT"', help="English text (words; [p h o n e s] in brackets for others)")
    src.add_argument("--utterance", metavar="ID", help="a corpus utterance: its own phone mid-points as targets "
                                                       "(kinematic landmarks when it has no phones)")
    src.add_argument("--states", metavar="S,S,...", help="state indices of the manifold's state graph as targets")
    p.add_argument("--key-frames", metavar="F,F,...|kinematic|gestures[:GONS+MAXC+GOFFS]", default=None,
                   help="with --utterance: target frames (0-based within the utterance), 'kinematic' for its "
                        "aperture maxima / minima and peak velocities, or 'gestures' for the gestural landmarks of "
                        "its lip aperture (default GONS+MAXC+GOFFS; any of GONS PVEL NONS MAXC NOFFS PVEL2 GOFFS)")
    p.add_argument("--spacing", type=float, default=0.2, metavar="SECONDS",
                   help="with --states: time between successive targets (default: %(default)s)")
    p.add_argument("--manifold", metavar="FILE", help="manifold file from 'lipspace build' (default: fit the "
                                                     "synthetic talker)")
    p.add_argument("--preset", choices=PRESETS, default="default",
                   help="synthetic talker preset without --manifold (default: %(default)s)")
    p.add_argument("--method", choices=(BEST,) + METHODS, default=BEST,
                   help="synthesis method: 'best' (default) takes the one measured best on the corpus's own "
                        "validation split for these targets (docs/RESULTS.md); manifold = learnt paths between "
                        "the states, viterbi = the paper's maximum-probability state path, sv-hermite = "
                        "state-velocity Hermite")
    add_synthesis_options(p)
    p.add_argument("-o", "--output", metavar="TRAJ.csv|TRAJ.npy|ANIM.glb",
                   help="write the trajectory (CSV or NPY), or a glTF morph-target animation (.glb or .gltf)")
    p.add_argument("--audio", metavar="FILE", help=".glb: audio written as a WAV beside it (default: the "
                                                   "--utterance's own, if any)")
    p.add_argument("--gltf-scale", type=float, default=0.001,
                   help=".glb: node scale from corpus units to metres (default: %(default)s, for millimetres)")
    p.add_argument("--values", choices=VALUES, default="frames",
                   help="what -o holds: lip frames, shape coordinates F^x or manifold coordinates F^y "
                        "(default: %(default)s)")
    p.add_argument("--mesh-dir", metavar="DIR", help="write one mesh file per frame into DIR")
    p.add_argument("--mesh-format", choices=("obj", "ply"), default="obj", help="mesh file format (default: obj)")
    p.add_argument("--praat", metavar="OUT.TextGrid",
                   help="write the synthesis for Praat: OUT.TextGrid (the input's span and phones, the targets, the "
                        "landmarks of the synthesised opening) and OUT.csv (the synthesised aperture per frame), "
                        "on the input TextGrid's timeline")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")


def add_synthesis_options(p):
    """The manifold method's options and the target timing options, shared with ``lipspace render``."""
    p.add_argument("--strict", action="store_true",
                   help="viterbi method: fail when a target cannot be reached in time (default: undershoot and warn)")
    p.add_argument("--candidates", type=int, default=8,
                   help="viterbi method: candidate states per phone (default: %(default)s)")
    p.add_argument("--inverse-dims", type=int, default=None,
                   help="viterbi method: dims of F^y used by the Y -> X inverse map (default: 3, the paper's)")
    p.add_argument("--inverse", choices=INVERSES, default="delaunay",
                   help="viterbi method: Y -> X map of the state path: the paper's 3-D Delaunay interpolation, "
                        "each state's mean X, or local-linear regression on the k nearest frames in F^y "
                        "(docs/RESULTS.md compares them; default: %(default)s)")
    p.add_argument("--smoothing", type=float, default=0.0, metavar="FRAMES",
                   help="viterbi method: Gaussian smoothing (s.d. in frames) of the state path before the "
                        "inverse map (default: %(default)s)")
    p.add_argument("--tier", default=None, help="TextGrid tier holding the phones (default: found by name)")
    p.add_argument("--tempo", type=float, default=1.0, help="--text: speaking-rate factor (default: %(default)s)")


def _manifold(args):
    from app.cli import CliError
    from app.cli._common import load_manifold_arg, progress_bar

    if args.manifold:
        return load_manifold_arg(args.manifold)
    from app.files.source_loading import load_source

    # the talker the window opens: its cached (or shipped) manifold, fitted and cached when there is none
    with progress_bar(disable=True if args.quiet else None) as progress:
        try:
            return load_source(None, args.preset, progress, prepare_views=False)[0]
        except ValueError as exc:
            raise CliError(str(exc)) from None


def _targets(args, manifold):
    from engine.phonetics import targets as T

    if args.phones is not None:
        return T.targets_from_phones(manifold, args.phones)
    if args.textgrid is not None:
        if not Path(args.textgrid).exists():
            raise FileNotFoundError(f"{args.textgrid}: no such TextGrid file")
        return T.targets_from_textgrid(manifold, args.textgrid, tier=args.tier)
    if args.text is not None:
        from engine.phonetics.phones import DurationModel

        return T.targets_from_text(manifold, args.text, duration_model=DurationModel(tempo=args.tempo))
    if args.states is not None:
        try:
            states = [int(x) for x in args.states.replace(" ", ",").split(",") if x.strip()]
        except ValueError:
            raise ValueError(f"--states {args.states!r}: expected comma-separated state indices") from None
        if not states or not args.spacing > 0:
            raise ValueError("--states needs at least one state and --spacing > 0 seconds")
        step = max(1, int(round(args.spacing * manifold.corpus_.rate)))
        return T.targets_from_points(manifold, [(k * step, s) for k, s in enumerate(states)],
                                     n_frames=(len(states) - 1) * step + 1)
    kf = _key_frames(args, manifold) if args.key_frames is not None else None  # no phones: kinematic landmarks
    return T.targets_from_utterance(manifold, args.utterance, on_collision="merge", key_frames=kf)


def _key_frames(args, manifold):
    spec = args.key_frames.strip()
    if spec == "kinematic":
        from engine.recordings.kinematics import kinematic_key_frames, lip_aperture

        c = manifold.corpus_
        if lip_aperture(c) is None:
            raise ValueError(f"utterance {args.utterance!r} has no phones and {c.name} names no upper/lower lip "
                             "points for kinematic landmarks; give --key-frames F,F,... (frames within the "
                             "utterance)")
        return kinematic_key_frames(c, args.utterance)
    if spec.split(":")[0] == "gestures":  # gestural landmarks of the lip aperture (engine.recordings.signals.gestures)
        from engine.recordings.signals.gestures import find_gestures, gesture_key_frames

        marks = [m for m in spec.partition(":")[2].split("+") if m] or ["GONS", "MAXC", "GOFFS"]
        c = manifold.corpus_
        kf = gesture_key_frames(find_gestures(c, "lip_aperture"), args.utterance, c.bounds, landmarks=marks)
        if not kf.size:
            raise ValueError(f"utterance {args.utterance!r}: no gestures of the lip aperture found; give --key-frames "
                             "F,F,... or 'kinematic'")
        return kf
    try:
        return [int(x) for x in spec.replace(" ", ",").split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"--key-frames {spec!r}: expected comma-separated frame indices, 'kinematic' or "
                         "'gestures[:LANDMARK+...]'") from None


def _synthesizer(args, manifold, targets=None):
    """The fitted synthesiser of ``args.method``; ``"best"`` is resolved for ``targets`` first
    (``args.method`` then names the method, ``args.method_note`` says why)."""
    from app.models.trajectories import method_params, resolve_method
    from engine.synthesis.methods import make_synthesizer

    cache = getattr(args, "_synth_cache", None)
    if cache is None:
        cache = args._synth_cache = {}
    progress = _validation_progress(args)
    method, note = resolve_method(manifold, targets, args.method, cache, progress=progress)
    args.method, args.method_note = method, note
    if method == "viterbi":
        return make_synthesizer("viterbi", manifold, strict=args.strict, n_candidates=args.candidates,
                                inverse_dims=args.inverse_dims, inverse=args.inverse, smoothing=args.smoothing)
    return make_synthesizer(method, manifold, **method_params(manifold, method, cache, progress=progress))


def _validation_progress(args):
    """A progress callback that tells, once, that the corpus's methods are being measured (stderr)."""
    if getattr(args, "quiet", False):
        return None
    said = []

    def progress(stage, i, n):
        if stage == "validation" and not said:
            said.append(1)
            print("lipspace synthesize: measuring the synthesis methods on this corpus's validation split "
                  "(once per corpus; cached)...", file=sys.stderr, flush=True)

    return progress


def run(args) -> int:
    from app.cli import CliError
    from app.cli._common import check_synthesis_bounds, command_outputs

    out = Path(args.output) if args.output else None
    if out is not None and out.suffix.lower() not in (".csv", ".npy", ".glb", ".gltf"):
        raise CliError(f"{out}: the trajectory file must end in .csv or .npy (or .glb/.gltf for an animation)")
    if out is not None and out.suffix.lower() in (".glb", ".gltf") and args.values != "frames":
        raise CliError(f"--values {args.values} is for .csv/.npy; a glTF animation always holds the lip frames")
    if args.values == "fy" and args.method != "viterbi":
        raise CliError(f"--values fy needs --method viterbi (the {args.method} method moves in X, not Y)")
    if args.key_frames is not None and args.utterance is None:
        raise CliError("--key-frames picks frames of an utterance: give --utterance ID too")
    check_synthesis_options(args)
    praat = _praat_paths(args)
    said = []  # what to print once every output is in place
    with command_outputs(args) as outputs:  # all outputs or none, also on Ctrl-C / SIGTERM
        animation = out is not None and out.suffix.lower() in (".glb", ".gltf")
        if animation:
            _refuse_existing_animation(args, out)
        staged = outputs.file(out, option="-o") if out is not None and not animation else None
        staged_praat = None if praat is None else [outputs.file(p, option="--praat") for p in praat]
        mesh_dir = None
        if args.mesh_dir:  # a frame sequence: any older frame file would be read back with it
            mesh_dir = outputs.folder(args.mesh_dir, pattern=f"frame_*.{args.mesh_format}", exclusive=True,
                                      option="--mesh-dir")
        manifold = _manifold(args)
        try:
            targets = _targets(args, manifold)
            check_synthesis_bounds(args, targets)
            traj = _synthesizer(args, manifold, targets).synthesize(targets)
        except (ValueError, FileNotFoundError) as exc:
            raise CliError(str(exc)) from None
        for w in traj.warnings:
            print(f"warning: {w}", file=sys.stderr)
        if args.method_note:
            print(args.method_note)
        frames = traj.frames(manifold)
        c = manifold.corpus_
        print(f"{traj.method}: {traj.n_frames} frames ({traj.n_frames / targets.rate:.2f} s at {targets.rate:g} Hz) "
              f"through {len(targets.targets)} targets from {targets.source}: "
              f"{' '.join(t.label or '?' for t in targets.targets[:30])}{' ...' if len(targets.targets) > 30 else ''}")
        if animation:
            said.append(_write_animation(args, manifold, traj, out, outputs))
        elif out is not None:
            from engine.io.writers.export import corpus_columns, write_trajectory_csv, write_trajectory_npy

            if args.values == "frames":
                values, cols = frames, corpus_columns(c)
            elif args.values == "fx":
                values, cols = traj.Fx, [f"x{k + 1}" for k in range(traj.Fx.shape[1])]
            else:
                values, cols = traj.Fy, [f"y{k + 1}" for k in range(traj.Fy.shape[1])]
            if out.suffix.lower() == ".csv":
                write_trajectory_csv(staged, values, times=traj.times, columns=cols)
            else:
                write_trajectory_npy(staged, values)
            said.append(f"wrote {out} ({values.shape[0]} frames x {values.shape[1]} values: "
                        f"{_values_meaning(args.values, c)})")
        if praat is not None:
            said.append(_write_praat(args, manifold, targets, traj, praat, staged_praat))
        if mesh_dir is not None:
            from engine.io.writers.export import write_mesh_sequence
            from engine.recordings.lipcontour import mesh_geometry

            try:
                # sparse lip markers: a contour tube, plus one labelled vertex per sensor
                pts, faces, note, labels = mesh_geometry(frames, c, sensors=True)
                files = write_mesh_sequence(mesh_dir, pts, faces=faces, dims=c.dims, format=args.mesh_format,
                                            labels=labels)
            except ValueError as exc:
                raise CliError(str(exc)) from None
            said.append(f"wrote {len(files)} {args.mesh_format.upper()} files to {args.mesh_dir}"
                        + (f" ({note})" if note else ""))
    for line in said:
        print(line)
    return 0


def _praat_paths(args):
    """``(OUT.TextGrid, OUT.csv, OUT.csv.json)`` of ``--praat`` (None without it)."""
    if args.praat is None:
        return None
    from app.cli import CliError
    from engine.io.writers.tidy import sidecar_path

    grid = Path(args.praat)
    if grid.suffix.lower() != ".textgrid":
        raise CliError(f"--praat {grid}: give the TextGrid to write (OUT.TextGrid); OUT.csv goes beside it")
    return grid, grid.with_suffix(".csv"), sidecar_path(grid.with_suffix(".csv"))


def _write_praat(args, manifold, targets, traj, paths, staged) -> str:
    """``--praat``: the synthesis as a TextGrid and a CSV on the input alignment's timeline, written to
    the ``staged`` paths of ``paths``; returns the line to print once they are in place."""
    from engine.io.writers.praat import write_textgrid
    from engine.io.writers.tidy import write_frame_table
    from engine.synthesis.tiers import input_timeline, synthesis_outputs

    timeline = input_timeline(args.textgrid, tier=args.tier) if args.textgrid is not None else None
    table, (xmin, xmax, tiers) = synthesis_outputs(manifold, targets, traj, timeline=timeline)
    write_frame_table(staged[1], table, sidecar=staged[2], name=paths[1].name)
    write_textgrid(staged[0], xmin, xmax, tiers)
    opening = [n for n in table.columns if n in ("lip_aperture", "opening_fx1")][0]
    return (f"wrote {paths[0]} (tiers {', '.join(t.name for t in tiers)}; {xmin:g}-{xmax:g} s"
            f"{', as the input' if timeline is not None else ''}) and {paths[1]} ({table.n_rows} frames: time_s, "
            f"{opening}, ...; units in {paths[2].name})")


#: largest --smoothing (s.d. in frames): a minute at 60 Hz; more flattens any utterance to its mean
MAX_SMOOTHING_FRAMES = 3600.0


def check_synthesis_options(args) -> None:
    """Refuse numeric options no synthesis can use (non-finite, negative, absurdly large), naming them."""
    import math

    from app.cli import CliError

    sm = getattr(args, "smoothing", None)
    if sm is not None and not (math.isfinite(sm) and 0 <= sm <= MAX_SMOOTHING_FRAMES):
        raise CliError(f"--smoothing {sm:g}: must be from 0 to {MAX_SMOOTHING_FRAMES:g} frames (the s.d. of the "
                       "Gaussian that smooths the state path; 0 = none)")
    cand = getattr(args, "candidates", None)
    if cand is not None and not 1 <= cand <= 1000:
        raise CliError(f"--candidates {cand}: must be from 1 to 1000 states per phone")
    sp = getattr(args, "spacing", None)
    if getattr(args, "states", None) is not None and sp is not None and not (math.isfinite(sp) and 0 < sp <= 60):
        raise CliError(f"--spacing {sp:g}: must be above 0 and at most 60 seconds between targets")
    gs = getattr(args, "gltf_scale", None)
    if gs is not None and not (math.isfinite(gs) and 0 < gs <= 1e6):
        raise CliError(f"--gltf-scale {gs:g}: must be a positive number (0.001 turns millimetres into metres)")


def _refuse_existing_animation(args, out) -> None:
    """Refuse an existing ``-o`` animation, or WAV beside it, before any synthesis (the choice of
    method can take minutes); :func:`_write_animation` stages them later."""
    from engine.files.staging import OutputExistsError

    if args.force:
        return
    wav = out.with_suffix(".wav")
    with_audio = args.audio is not None or args.utterance is not None
    if out.exists():
        raise OutputExistsError(out, "-o")
    if with_audio and wav.exists() and not (args.audio is not None and Path(args.audio).resolve() == wav.resolve()):
        raise OutputExistsError(wav, "the audio beside it")


def _write_animation(args, manifold, traj, out, outputs) -> str:
    """``-o speech.glb``: the trajectory as glTF morph weights, its audio as a WAV beside it, staged
    in ``outputs``; returns the line to print once they are in place."""
    from app.cli import CliError
    from app.export.animation import export_animation, utterance_audio

    audio = None
    if args.audio is not None:
        if not Path(args.audio).is_file():
            raise CliError(f"--audio {args.audio}: no such file")
        audio = args.audio
    elif args.utterance is not None:
        audio, why = utterance_audio(manifold, args.utterance, args.manifold)
        if audio is None:
            print(f"lipspace synthesize: note: {why}; no WAV beside {out.name}", file=sys.stderr)
    try:
        files = export_animation(manifold, traj.Fx, out, rate=manifold.corpus_.rate, audio=audio,
                                 scale=args.gltf_scale, source=f"{traj.method}: {args.utterance or 'synthesis'}",
                                 outputs=outputs)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    m = traj.Fx.shape[1]
    return (f"wrote {', '.join(str(f) for f in files)} ({traj.n_frames} frames; {m} shape components as {2 * m} "
            "morph targets X1+, X1-, ...)")
