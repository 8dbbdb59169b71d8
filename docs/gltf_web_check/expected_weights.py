"""Write the morph weights a glTF viewer should show, for docs/gltf_web_check/check.html.

Usage: .venv/bin/python docs/gltf_web_check/expected_weights.py speech.glb expected.json

Reads the file back with engine.io.writers.gltf.read_gltf_morph (pygltflib) and writes, as JSON,
the number of morph targets, the animation's duration, and at 12 times (6 keyframes and
the midpoints after them, where LINEAR interpolation gives the mean of the two keys) the
expected morph weights and the first 10 deformed vertices (base + weights @ targets, in
the file's own units, before the node scale). A developer check, not part of the package.
"""
import json
import sys

import numpy as np

from engine.io.writers.gltf import read_gltf_morph


def main(src, dst):
    d = read_gltf_morph(src)
    t = d["times"].astype(np.float64)
    W = d["weights"].astype(np.float64)
    base = d["base"].astype(np.float64)
    T = d["targets"].astype(np.float64)
    n = len(t)
    if n < 3:
        raise SystemExit(f"{src}: {n} frames; the check needs at least 3")
    samples = []
    for i in sorted({0, 1, n // 4, n // 2, (3 * n) // 4, n - 2}):
        for tt, w, kind in ((t[i], W[i], f"frame {i}"),
                            (0.5 * (t[i] + t[i + 1]), 0.5 * (W[i] + W[i + 1]), f"mid {i}-{i + 1}")):
            pos = base + np.tensordot(w, T, axes=1)
            samples.append({"t": float(tt), "w": w.tolist(), "kind": kind, "pos": pos[:10].ravel().tolist()})
    out = {"n_targets": int(T.shape[0]), "n_vertices": int(base.shape[0]), "duration": float(t[-1]),
           "n_frames": n, "interpolation": d["interpolation"], "target_names": d["target_names"],
           "scale": d["scale"], "samples": samples}
    with open(dst, "w") as f:
        json.dump(out, f)
    print(f"{src}: {T.shape[0]} targets, {base.shape[0]} vertices, {n} frames, "
          f"{t[-1]:.4f} s, {d['interpolation']}, weights in [{W.min():.3f}, {W.max():.3f}]")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    main(sys.argv[1], sys.argv[2])
