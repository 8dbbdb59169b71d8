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

from app.cli.options import add_quiet_option, add_talker_options
from app.cli.synthesis_steps import (
    BEST,
    INVERSES,
    METHODS,
    add_synthesis_options,
    check_synthesis_options,
    load_manifold,
    make_synthesizer,
    make_targets,
)

__all__ = ["add_arguments", "run", "METHODS", "INVERSES", "BEST", "VALUES"]

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
    src.add_argument("--phones", metavar='"P DUR ..."',
                     help='phone labels with durations in seconds, e.g. "p 0.08 ax 0.1"')
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
    add_talker_options(p, when="without --manifold")
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
    add_quiet_option(p)


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
        manifold = load_manifold(args)
        try:
            targets = make_targets(args, manifold)
            check_synthesis_bounds(args, targets)
            traj = make_synthesizer(args, manifold, targets).synthesize(targets)
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
