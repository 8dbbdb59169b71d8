"""Robust scale of G's blocks: one glitch frame must not set the scale of the whole velocity block."""
import warnings

import numpy as np
import pytest

from engine.manifold.dynamics import OUTLIER_RATIO, DynamicFeatures, DynamicScaleWarning
from engine.recordings.bounds import velocities


def _smooth_track(n=600, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 60.0
    Fx = np.column_stack([np.sin(2 * np.pi * 3 * t), 0.5 * np.cos(2 * np.pi * 2 * t)])
    return (Fx + 0.01 * rng.standard_normal(Fx.shape)).astype(np.float32), np.array([[0, n]])


def test_clean_data_fits_silently_and_reports_its_ratio(small_manifold):
    Fx, b = _smooth_track()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = DynamicFeatures().fit(Fx, b)
    assert 1.0 <= d.shape_outlier_ratio_ < OUTLIER_RATIO and 1.0 <= d.velocity_outlier_ratio_ < OUTLIER_RATIO
    # the synthetic talker is clean too (measured ratio about 1.6 / 1.9)
    m = small_manifold
    ratio = DynamicFeatures().fit(m.Fx_, m.corpus_.bounds).velocity_outlier_ratio_
    assert ratio < OUTLIER_RATIO


def test_a_glitch_warns_and_p99_scaling_ignores_it():
    Fx, b = _smooth_track()
    Fx[300] += 40.0  # one tracking glitch: a jump out and back
    with pytest.warns(DynamicScaleWarning) as rec:
        d_max = DynamicFeatures().fit(Fx, b)
    msgs = [str(w.message) for w in rec]
    assert any("velocity block of G" in m and "--dynamics-scale p99" in m for m in msgs), msgs
    assert any("shape block of G" in m for m in msgs), msgs
    with pytest.warns(DynamicScaleWarning) as rec:
        d_p99 = DynamicFeatures(scale="p99").fit(Fx, b)
    assert not any("--dynamics-scale p99" in str(w.message) for w in rec)  # no hint to do what is done
    V = velocities(Fx, b)
    Gv = np.abs(d_p99.transform(Fx, b)[:, 2:])
    assert np.percentile(Gv, 99) == pytest.approx(1.0, rel=1e-4)
    # with max scaling the glitch squeezes every ordinary frame's velocity towards 0
    ordinary = np.abs(V[:, 0]) < np.percentile(np.abs(V[:, 0]), 90)
    spread_max = np.abs(d_max.transform(Fx, b)[ordinary, 2:]).mean()
    spread_p99 = Gv[ordinary].mean()
    assert spread_p99 > 5 * spread_max, (spread_p99, spread_max)
    assert d_p99.get_params() == {"scale": "p99"}


def test_bad_scale_is_rejected():
    Fx, b = _smooth_track()
    for bad in ("median", "p10", "p101", 3):
        with pytest.raises(ValueError, match="scale must be 'max' or a percentile"):
            DynamicFeatures(scale=bad).fit(Fx, b)
