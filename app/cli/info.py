"""``lipspace info``: summarise a corpus or manifold file."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from app.files.source_loading import (
    ANALYSIS_RATE,  # the paper's 60 Hz, which velocities and the state graph are tuned to
)


def add_arguments(p):
    p.add_argument("file", help="a manifold (from 'lipspace build') or native corpus file (.npz)")


def _corpus_lines(c):
    mids, labels, *_ = c.phone_table()
    uniq, counts = np.unique(labels, return_counts=True) if len(labels) else ([], [])
    top = ", ".join(f"{u} {n}" for u, n in sorted(zip(uniq, counts), key=lambda t: -t[1])[:12])
    n_utt = len(c.utterances)
    return [
        f"corpus      {c.name}",
        f"frames      {c.n_frames} at {c.rate:g} Hz ({c.duration:.1f} s), {n_utt} utterance{'s' * (n_utt != 1)}"
        + ("" if abs(c.rate - ANALYSIS_RATE) <= 0.05 * ANALYSIS_RATE else
           f" (the method's analysis rate is {ANALYSIS_RATE:g} Hz: 'lipspace import --resample {ANALYSIS_RATE:g}')"),
        f"points      {c.n_points} ({c.dims}-D){f', mesh with {len(c.faces)} faces' if c.faces is not None else ''}",
        f"phones      {len(labels)} intervals, {len(uniq)} labels" + (f"; most frequent: {top}" if top else ""),
        f"latent      {', '.join(sorted(k for k in c.latent if not k.startswith('quality_'))) or '-'}",
    ] + _recording_lines(c)


def _recording_lines(c):
    """Speakers, sensor roles, registration and import history of a corpus."""
    spk = [s for s in c.speakers if s]
    lines = []
    if not any(u.phones for u in c.utterances):
        lips = c.role_points("upper_lip").size and c.role_points("lower_lip").size
        lines.append("labels      none: " + ("clusters, synthesize --utterance, evaluate and figures use kinematic "
                                             "landmarks (aperture maxima/minima, peak velocities)" if lips else
                                             "no lip roles for kinematic landmarks either; synthesize with "
                                             "--states or --utterance ID --key-frames F,F,..."))
    if spk:
        lines.append(f"speakers    {len(spk)}: {', '.join(spk[:12])}{' ...' if len(spk) > 12 else ''}")
    from engine.recordings.metadata import describe_fields

    lines += [f"{'fields' if i == 0 else '':<11} {text}" for i, text in enumerate(describe_fields(c))]
    quality = [h[len("quality: "):] for h in c.history if h.startswith("quality: ")]
    from engine.recordings.signals.quality import sensor_quality

    if quality or sensor_quality(c) is not None:
        quality = quality or ["sensor quality values kept; not reported on import (a corpus made before the report)"]
        lines += [f"{'quality' if i == 0 else '':<11} {text}" for i, text in enumerate(quality)]
    if c.point_roles is not None:
        from app.cli._common import roles_text

        lines.append("roles       " + roles_text(c.point_names, c.point_roles))
    from engine.recordings.orientation import anatomical_frame

    lines.append(f"orientation {anatomical_frame(c).describe()}")
    lines.append(f"registration {c.registration or 'none'}")
    lines += [f"history     {h}" for h in c.history if not h.startswith(("read ", "registration:", "quality: "))]
    return lines


def _opening_lines(m):
    """How "opening" is defined and how well the tangent classes follow the lip aperture."""
    import warnings

    from engine.manifold.class_agreement import ACCELERATING_BOUND, OPENING_BOUND, class_agreement
    from engine.recordings.kinematics import aperture_definition, lip_aperture

    c, t = m.corpus_, m.tangent_
    scores = t.neighbor_scores_
    how = (f"tangent frames in {t.n_dims_} dims of Y over {t.n_neighbors_} neighbours"
           + (" (chosen by held-out validation)" if len(scores) else " (as given)"))
    lines = [f"opening     defined by {aperture_definition(c)}", f"            {how}"]
    ap = lip_aperture(c)
    if ap is None:
        return lines + ["classes vs  the lip aperture: not measurable (no lip aperture)"]
    agree = class_agreement(t.opening_, t.accelerating_, ap, c.bounds)
    lines.append(f"classes vs  the lip aperture: {agree.describe()}")
    if agree.opening >= OPENING_BOUND and agree.accelerating >= ACCELERATING_BOUND:
        return lines
    causes = []
    if (c.point_roles or []) and "tongue" in c.point_roles:
        n_t = c.point_roles.count("tongue")
        causes.append(f"{n_t} tongue sensor{'s' * (n_t != 1)} in the shape space move the manifold without "
                      "the lips (import with --points naming the lip sensors only)")
    if not c.registration and len(c.utterances) > 1:
        causes.append("no registration: offsets between recordings move the manifold without the lips (import "
                      "with --register utterance, or rigid with reference sensors)")
    if len([s for s in c.speakers if s]) > 1 and getattr(m, "speaker_normalisation", "auto") == "none":
        causes.append("several speakers without per-speaker normalisation (build --speaker-norm mean)")
    second = agree.accelerating_second_difference
    if agree.accelerating < ACCELERATING_BOUND and second < ACCELERATING_BOUND + 0.05:
        slow = c.rate < 0.9 * ANALYSIS_RATE
        causes.append(f"the aperture's velocity changes sign between neighbouring frames so often that even the "
                      f"aperture's own second difference gets the speed change right on only "
                      f"{100 * second:.1f}% of frames"
                      + (f"; at {c.rate:g} Hz a frame spans too much of a movement: import the recording with "
                         f"--resample {ANALYSIS_RATE:g} (the analysis rate)" if slow else
                         "; the lip measurements are noisy at this frame rate"))
    if not causes:
        causes.append(f"the lips' movement is a small part of what varies in Y ({t.n_dims_} dims): other "
                      "movements or measurement noise dominate the neighbourhoods; no build option changes that")
    from engine.recordings.corpus import CorpusWarning

    warnings.warn(CorpusWarning(f"the tangent classes agree with the lip aperture less than expected (opening "
                                f"{100 * agree.opening:.1f}%, expected >= {100 * OPENING_BOUND:.0f}%; accelerating "
                                f"{100 * agree.accelerating:.1f}%, expected >= {100 * ACCELERATING_BOUND:.0f}%); "
                                f"cause: {'; '.join(causes)}"), stacklevel=2)
    return lines


def _refuse_foreign(path: Path) -> None:
    """A recording in a format the importers read (.mat, .ema, .c3d, .csv ...) is not a
    Lipspace file: say what it is and how to import it, instead of a zip error."""
    from app.cli import CliError

    if path.is_dir():
        raise CliError(f"{path}: is a directory; give a Lipspace corpus or manifold file (.npz)")
    with open(path, "rb") as fh:
        if fh.read(4) == b"PK\x03\x04":
            return  # a zip: the loaders below say what is wrong with it
    # only for a file that is not a Lipspace .npz: summarising one never loads the importers
    from engine.io import ImportFormatError
    from engine.io.dispatch import FORMATS, detect_format
    try:
        fmt = detect_format(path)
    except (ImportFormatError, OSError, ValueError):
        fmt = None
    if fmt is None or fmt == "npz":
        raise CliError(f"{path}: not a Lipspace corpus or manifold file (those are .npz files written by "
                       "'lipspace import' and 'lipspace build')")
    raise CliError(f"{path}: a recording in the {fmt!r} format ({FORMATS[fmt][2]}), not a Lipspace corpus or "
                   f"manifold file; import it first: lipspace import {path} -o corpus.npz")


def run(args) -> int:
    from app.cli import CliError
    from engine.manifold.model import Manifold, ManifoldFileError

    path = Path(args.file)
    if not path.exists():
        raise CliError(f"{path}: no such file")
    _refuse_foreign(path)
    try:
        m = Manifold.load(path)
    except ManifoldFileError as exc:
        if "corpus file" not in str(exc):
            raise CliError(str(exc)) from None
        from app.cli._common import load_corpus_arg

        c = load_corpus_arg(path)  # a corpus stored in blocks is read from them, not gathered
        print(f"{path}: Lipspace corpus")
        print("\n".join(_corpus_lines(c)))
        return 0
    print(f"{path}: Lipspace manifold")
    print("\n".join(_corpus_lines(m.corpus_)))
    sh, emb = m.shape_, m.embedding_
    k = sh.n_components_
    print(f"shape X     {k} components hold {100 * sh.recovered_ratio_[k - 1]:.2f}% of the variance of the "
          f"{len(sh.scree_)} computed ({100 * sh.explained_variance_ratio_.sum():.2f}% of the total); "
          f"scree {', '.join(f'{100 * v:.1f}' for v in sh.scree_[:5])}%")
    from engine.talker.report import components_of_total

    n_comp = len(sh.scree_)
    (n_total,) = components_of_total(sh.scree_, (0.95,))
    n_total = f"more than {n_comp}" if n_total is None else str(n_total)
    n_rec = int(np.searchsorted(sh.recovered_ratio_, 0.95 - 1e-12)) + 1
    print(f"            95% of the total variance takes {n_total} components; 95% of the {n_comp} computed "
          f"components' variance (the paper's \"recovered variance\") takes {n_rec}")
    rr = emb.recovered_ratio_
    print(f"embedding Y {m.embedding_method}, {m.Fy_.shape[1]} dims"
          + (f", {len(emb.landmarks_)} landmarks" if emb.landmarks_ is not None else "")
          + f"; first 3 dims hold {100 * rr[min(2, len(rr) - 1)]:.1f}% of the recovered variance "
          f"(per dim {', '.join(f'{100 * v:.1f}' for v in np.diff(np.r_[0, rr])[:5])}%)")
    props = m.tangent_.class_proportions()
    print("classes     " + "; ".join(f"{name} {100 * v:.1f}%" for name, v in props.items()))
    print("\n".join(_opening_lines(m)))
    print("state graph " + m.states_.connectivity_report().replace("\n", "\n            "))
    if m.timings_:
        print("fit time    " + ", ".join(f"{k} {v:.2f} s" for k, v in m.timings_.items()))
    return 0
