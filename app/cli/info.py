"""``lipspace info``: summarise a corpus or manifold file."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from app.source_loading import ANALYSIS_RATE  # the paper's 60 Hz, which velocities and the state graph are tuned to


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
        f"points      {c.n_points} ({c.dims}-D){', mesh with %d faces' % len(c.faces) if c.faces is not None else ''}",
        f"phones      {len(labels)} intervals, {len(uniq)} labels" + (f"; most frequent: {top}" if top else ""),
        f"latent      {', '.join(sorted(c.latent)) or '-'}",
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
    if c.point_roles is not None:
        from app.cli._common import roles_text

        lines.append("roles       " + roles_text(c.point_names, c.point_roles))
    from engine.orientation import anatomical_frame

    lines.append(f"orientation {anatomical_frame(c).describe()}")
    lines.append(f"registration {c.registration or 'none'}")
    lines += [f"history     {h}" for h in c.history if not h.startswith(("read ", "registration:"))]
    return lines


def _wider_neighbourhood(m, aperture):
    """(k, agreement) when tangent frames over k = max(2 x, 0.3% of the frames) neighbours agree with the
    aperture at least 5 points better than the manifold's own, else None (refits only the tangent frames)."""
    from engine.kinematics import opening_agreement
    from engine.tangent import TangentFrames

    t = m.tangent_
    N = m.Fy_.shape[0]
    k2 = int(max(2 * t.n_neighbors, round(0.003 * N)))
    if k2 >= N:
        return None
    tf = TangentFrames(n_neighbors=k2, n_dims=t.n_dims, zero_velocity_quantile=t.zero_velocity_quantile,
                       local_plane=t.local_plane).fit(m.Fy_, m.Fx_, m.Fxv_, m.corpus_.bounds, opening=aperture)
    base = opening_agreement(t.opening_, aperture, m.corpus_.bounds)
    agree2 = opening_agreement(tf.opening_, aperture, m.corpus_.bounds)
    return (k2, agree2) if agree2 >= base + 0.05 else None


def _opening_lines(m):
    """How "opening" is defined and how well the opening class follows the lip aperture."""
    import warnings

    from engine.kinematics import AGREEMENT_WARN_BELOW, lip_aperture, opening_agreement

    c = m.corpus_
    source = getattr(m.tangent_, "opening_source_", "F^x_1")
    ap = lip_aperture(c)
    if ap is None:
        return [f"opening     defined by {source} (the corpus names no upper_lip / lower_lip points, so the "
                "aperture cannot be checked; import with --layout to name them)"]
    agree = opening_agreement(m.tangent_.opening_, ap, c.bounds)
    lines = [f"opening     defined by {source}; agreement of the opening class with the lip aperture "
             f"increasing: {100 * agree:.1f}% of moving frames"]
    if not agree >= AGREEMENT_WARN_BELOW:
        causes = []
        if source != "lip aperture":
            causes.append("opening follows the first shape component, not the aperture (rebuild: the layout's "
                          "upper/lower lip roles make the aperture the reference)")
        if (c.point_roles or []) and "tongue" in c.point_roles:
            n_t = c.point_roles.count("tongue")
            causes.append(f"{n_t} tongue sensor{'s' * (n_t != 1)} in the shape space (import with --points to "
                          "keep the lip sensors only)")
        if not c.registration:
            causes.append("no registration (import with --register utterance, or rigid with reference sensors)")
        if len([s for s in c.speakers if s]) > 1 and getattr(m, "speaker_normalisation", "auto") == "none":
            causes.append("several speakers without per-speaker normalisation (build --speaker-norm mean)")
        if source == "lip aperture" and m.Fy_.shape[1] >= 3:
            wider = _wider_neighbourhood(m, ap)
            if wider is not None:
                k2, agree2 = wider
                causes.append(f"tangent neighbourhoods of {m.tangent_.n_neighbors} frames are small for "
                              f"{c.n_frames} frames ('lipspace build --neighbors {k2}' gives {100 * agree2:.1f}%)")
        if not causes:
            causes.append("opening shares the first three dimensions of Y with other lip movements (rounding, "
                          "protrusion) or is small against sensor noise; check the lip sensors' roles")
        from engine.corpus import CorpusWarning

        warnings.warn(CorpusWarning(f"the opening class agrees with the lip aperture velocity on only "
                                    f"{100 * agree:.1f}% of moving frames (expected >= "
                                    f"{100 * AGREEMENT_WARN_BELOW:.0f}%); likely cause: {'; '.join(causes)}"))
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
    from engine.manifold import Manifold, ManifoldFileError

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
    from engine.talker_report import components_of_total

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
