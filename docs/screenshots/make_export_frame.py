"""Regenerate ``export_frame.png``: one frame of ``lipspace render`` (original beside the
manifold synthesis, with the manifold panel), decoded from the MP4 itself.

    .venv/bin/python docs/screenshots/make_export_frame.py MANIFOLD.npz UTTERANCE SECONDS docs/screenshots

MANIFOLD.npz: e.g. ``lipspace build -o talker.npz`` (the default synthetic talker).
"""
import sys
import tempfile
from pathlib import Path

import av

from app.cli import main
from engine.files.atomic import atomic_write

manifold, utt, at, outdir = sys.argv[1], sys.argv[2], float(sys.argv[3]), Path(sys.argv[4])
with tempfile.TemporaryDirectory() as tmp:
    mp4 = Path(tmp) / "talk.mp4"
    rc = main(["render", "--manifold", manifold, "--utterance", utt, "--side-by-side", "--trajectory",
               "--size", "560x420", "-q", "-o", str(mp4)])
    if rc:
        raise SystemExit(rc)
    with av.open(str(mp4)) as f:
        rate = f.streams.video[0].average_rate
        for k, frame in enumerate(f.decode(video=0)):  # noqa: B007 (the frame is used after the loop)
            if k >= round(at * rate):
                break
    with atomic_write(outdir / "export_frame.png") as png:
        frame.to_image().save(png, format="PNG")
print(f"wrote {outdir / 'export_frame.png'} (frame {k}, {float(k / rate):.2f} s)")
