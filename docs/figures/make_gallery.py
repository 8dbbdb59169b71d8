"""Regenerate the figure gallery (docs/figures/README.md and its PNGs): every figure at one journal column.

    .venv/bin/python docs/figures/make_gallery.py            # all corpora (the video one needs the [video] extra)

Four corpora of the kinds users bring, made the way real recordings are (engine.talker.example_corpora):
the synthetic talker (a lip mesh with phones), a 4-sensor articulograph corpus of three speakers without
phone labels, a MOCHA-style 2-D midsagittal corpus with .lab alignments, and a talking-face video corpus.
Every figure is rendered at 85 mm exactly as ``lipspace figures --width 85mm`` renders it (the same
function), written as PNG at 150 dpi, and listed in README.md with what it shows. Nothing here is edited by
hand: run this script after changing a figure.
"""
from __future__ import annotations

import sys
import tempfile
import time
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

#: the width the gallery shows (one journal column) and the PNGs' resolution
WIDTH_MM = 85.0
DPI = 150
#: which figures each corpus shows: the talker and the articulograph all of them, the others the figures their
#: kind of data changes (lip shapes, distances, a regenerated utterance)
SHOWN = {"talker": None, "articulograph": None, "midsagittal": ("fig1a", "fig2c", "fig2b", "fig3"),
         "video": ("fig1a", "fig2c", "fig2b", "fig3")}
TITLES = {"talker": "The synthetic talker: a lip mesh with phone labels",
          "articulograph": "A 4-sensor articulograph corpus (UL, LL, LC, RC), three speakers, no phone labels",
          "midsagittal": "A 2-D midsagittal corpus (MOCHA-style EST files: UL, LL, LI) with .lab alignments",
          "video": "A talking-face video corpus (80 FaceMesh lip landmarks, head pose removed)"}


def corpus_manifold(kind: str, folder: Path):
    """The manifold of corpus ``kind``, as ``lipspace import`` + ``build`` make it (or None: not available)."""
    from engine.manifold.model import Manifold
    from engine.talker import example_corpora as ex

    if kind == "talker":
        from engine.talker.synthetic import load_synthetic

        return Manifold().fit(load_synthetic(preset="small"))
    if kind == "articulograph":
        return Manifold(n_states=40).fit(ex.articulograph_corpus(n_speakers=3, n_utterances=3,
                                                                 duration_s=(2.0, 2.5), seed=5))
    if kind == "midsagittal":
        return Manifold(n_states=24).fit(ex.midsagittal_corpus(folder / "mocha"))
    try:
        import mediapipe  # noqa: F401
        import skimage  # noqa: F401
    except ImportError:
        return None
    return Manifold(n_states=24).fit(ex.video_corpus(folder / "video"))


def main() -> int:
    import app.figures as F
    from engine.recordings.kinematics import kinematic_if_unlabelled

    t0 = time.perf_counter()
    lines = ["# Figure gallery", "",
             "Every figure of `lipspace figures` (and of the window's File › Export figure, which calls the same",
             f"functions) at one journal column, {WIDTH_MM:g} mm wide, as a journal prints it: text of 6 pt or more,",
             "each axis spanning its data, the window's own colour maps for density and hop distance",
             "(`app.models.colour_maps`) and perceptually uniform ones elsewhere, categorical colours from the",
             "session palette. Sensor data are drawn as sensors: markers joined by straight lines, the lip",
             "aperture a dashed segment with its value.",
             "", "Made by `docs/figures/make_gallery.py` from generated corpora of four kinds; do not edit by hand.",
             ""]
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the generated recordings' import notes
        for kind, names in SHOWN.items():
            m = corpus_manifold(kind, Path(tmp))
            if m is None:
                print(f"{kind}: skipped (the [video] extra is not installed)")
                continue
            labelled = any(u.phones for u in m.corpus_.utterances)
            if not labelled:  # as lipspace figures does (and it skips fig4, which needs /b/ /p/ /m/)
                m.corpus_, _ = kinematic_if_unlabelled(m.corpus_)
            out = HERE / kind
            out.mkdir(exist_ok=True)
            lines += [f"## {TITLES[kind]}", ""]
            for name in names or F.FIGURES:
                if name == "fig4" and not labelled:
                    continue
                path = out / f"{name}.png"
                F.export_figure(name, m, path, width=WIDTH_MM / 25.4, dpi=DPI)
                _shrink(path)
                lines += [f"**{name}**: {F.DESCRIPTIONS[name]}", "", f"![{name}, {kind}]({kind}/{name}.png)", ""]
                print(f"{kind}/{name}.png")
    (HERE / "README.md").write_text("\n".join(lines))
    print(f"wrote {HERE / 'README.md'} in {time.perf_counter() - t0:.0f} s")
    return 0


def _shrink(path: Path) -> None:
    """Re-save a PNG with an optimised palette-free encoding (the same pixels, a smaller file)."""
    from PIL import Image

    with Image.open(path) as im:
        im.load()
        info = im.info.get("dpi")
    im.save(path, optimize=True, dpi=info)


if __name__ == "__main__":
    sys.exit(main())
