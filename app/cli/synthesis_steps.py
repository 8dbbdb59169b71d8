"""The synthesis steps ``lipspace synthesize`` and ``lipspace render`` share.

The manifold (``--manifold FILE`` or the synthetic talker's, ``--preset``), the targets
(``--phones``, ``--textgrid``, ``--text``, ``--utterance`` with ``--key-frames``, ``--states``),
the synthesiser of ``--method`` (``best`` resolved for the targets) and the synthesis options
(:func:`add_synthesis_options`) with their checks. Each step reads the parsed ``args`` of the
command that runs it; an option only one command has (``--states``, ``--key-frames``) is read
as absent where the command lacks it.
"""
from __future__ import annotations

import sys
from pathlib import Path

from engine.synthesis.methods import SYNTHESIS_METHODS

__all__ = ["METHODS", "BEST", "INVERSES", "MAX_SMOOTHING_FRAMES", "add_synthesis_options", "load_manifold",
           "make_targets", "key_frames", "make_synthesizer", "note_stale_choice", "validation_progress",
           "check_synthesis_options"]

#: the registry's methods (engine.synthesis.methods.SYNTHESIS_METHODS); "best" resolves to one of them
METHODS = tuple(SYNTHESIS_METHODS)
BEST = "best"
#: the manifold synthesiser's inverse maps (engine.synthesis.viterbi.INVERSES; a test keeps them equal)
INVERSES = ("delaunay", "state-mean", "local-linear")


def add_synthesis_options(p):
    """The manifold method's options and the target timing options."""
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


def load_manifold(args):
    """The manifold of ``--manifold FILE``, or the synthetic talker's of ``--preset`` (cached or shipped)."""
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


def make_targets(args, manifold):
    """The synthesis targets of whichever source option was given (``--phones``, ``--textgrid``,
    ``--text``, ``--states`` or ``--utterance``)."""
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
    states_spec = getattr(args, "states", None)  # lipspace synthesize only
    if states_spec is not None:
        try:
            states = [int(x) for x in states_spec.replace(" ", ",").split(",") if x.strip()]
        except ValueError:
            raise ValueError(f"--states {states_spec!r}: expected comma-separated state indices") from None
        if not states or not args.spacing > 0:
            raise ValueError("--states needs at least one state and --spacing > 0 seconds")
        step = max(1, int(round(args.spacing * manifold.corpus_.rate)))
        return T.targets_from_points(manifold, [(k * step, s) for k, s in enumerate(states)],
                                     n_frames=(len(states) - 1) * step + 1)
    key_spec = getattr(args, "key_frames", None)  # lipspace synthesize only
    kf = key_frames(args, manifold) if key_spec is not None else None  # no phones: kinematic landmarks
    return T.targets_from_utterance(manifold, args.utterance, on_collision="merge", key_frames=kf)


def key_frames(args, manifold):
    """The frames of ``--utterance`` that ``--key-frames`` names: indices, ``kinematic`` or ``gestures[:...]``."""
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


def make_synthesizer(args, manifold, targets=None):
    """The fitted synthesiser of ``args.method``; ``"best"`` is resolved for ``targets`` first
    (``args.method`` then names the method, ``args.method_note`` says why)."""
    from app.models.trajectories import method_params, resolve_method
    from engine.synthesis.methods import make_synthesizer as make

    cache = getattr(args, "_synth_cache", None)
    if cache is None:
        cache = args._synth_cache = {}
    note_stale_choice(args, manifold)
    progress = validation_progress(args)
    method, note = resolve_method(manifold, targets, args.method, cache, progress=progress)
    args.method, args.method_note = method, note
    if method == "viterbi":
        return make("viterbi", manifold, strict=args.strict, n_candidates=args.candidates,
                                inverse_dims=args.inverse_dims, inverse=args.inverse, smoothing=args.smoothing)
    return make(method, manifold, **method_params(manifold, method, cache, progress=progress))


def note_stale_choice(args, manifold) -> None:
    """Say once (stderr, not with ``-q``) when ``args.method`` reads a validated choice and the manifold file
    holds one other code measured (:func:`app.models.trajectories.stale_choice_note`)."""
    from app.models.trajectories import needs_choice, stale_choice_note

    if getattr(args, "quiet", False) or getattr(args, "_stale_said", False) or not needs_choice(args.method):
        return
    path = getattr(args, "manifold", None)
    note = stale_choice_note(manifold, Path(path).name if path else "the synthetic talker")
    if note is not None:
        args._stale_said = True
        print(f"lipspace synthesize: note: {note}", file=sys.stderr, flush=True)


def validation_progress(args):
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
