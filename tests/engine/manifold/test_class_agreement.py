"""engine.manifold.class_agreement: the classes against the aperture, the trivial rule and the second-difference
reading."""
import numpy as np
import pytest

from engine.manifold.class_agreement import MOVING_PER_FRAME, class_agreement
from engine.manifold.local_gradients import central_difference

RATE = 60.0


def _sine(n=600, f=2.0, amp=4.0):
    t = np.arange(n) / RATE
    return 10 + amp * np.sin(2 * np.pi * f * t), np.array([[0, n // 2], [n // 2, n]])


def _flags(a, bounds):
    v = central_difference(a, bounds)
    return v > 0, central_difference(np.abs(v), bounds) > 0


def test_exact_flags_agree_fully_and_inverted_flags_never():
    a, b = _sine()
    op, acc = _flags(a, b)
    got = class_agreement(op, acc, a, b)
    assert got.opening == 1.0 and got.accelerating == 1.0
    assert got.trivial_opening == 1.0 and got.trivial_accelerating == 1.0
    assert got.accelerating_second_difference > 0.97  # a smooth movement: one step reads the speed change
    bad = class_agreement(~op, ~acc, a, b)
    assert bad.opening == 0.0 and bad.accelerating == 0.0


def test_only_moving_frames_count_for_opening():
    a, b = _sine(amp=0.02)  # never faster than the threshold
    assert np.abs(central_difference(a, b)).max() < MOVING_PER_FRAME
    got = class_agreement(*_flags(a, b), a, b)
    assert got.n_opening == 0 and np.isnan(got.opening)
    assert got.n_accelerating > 0


def test_trivial_rule_reads_the_measured_aperture():
    a, b = _sine()
    noisy = a + np.random.default_rng(0).normal(0, 0.3, a.shape)
    op, acc = _flags(a, b)
    got = class_agreement(op, acc, a, b, measured=noisy)
    assert got.opening == 1.0
    assert 0.5 < got.trivial_opening < 0.99 and 0.4 < got.trivial_accelerating < 0.9
    assert "trivial rule" in got.describe() and "second difference" in got.describe()


def test_noise_lowers_the_second_difference_reading():
    a, b = _sine()
    rough = a + np.random.default_rng(1).normal(0, 1.0, a.shape)  # noise above a frame's movement
    smooth = class_agreement(*_flags(a, b), a, b).accelerating_second_difference
    noisy = class_agreement(*_flags(rough, b), rough, b).accelerating_second_difference
    assert noisy < smooth - 0.1


def test_shapes_are_checked():
    a, b = _sine()
    with pytest.raises(ValueError, match="one value per frame"):
        class_agreement(np.zeros(3, bool), np.zeros(3, bool), a, b)
