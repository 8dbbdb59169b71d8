"""The calibrated kinematics of the lip surface and the talker (LipModel(kinematics="calibrated"))."""
import numpy as np
import pytest

from engine.talker.lipmodel import CONTROL_NAMES, KINEMATICS, LipModel
from engine.talker.synthetic import SyntheticTalker
from engine.talker.virtual_sensors import SENSOR_ROLES, sensor_motion, virtual_sensors


def _controls(n=1, **values):
    c = np.zeros((n, len(CONTROL_NAMES)))
    for k, v in values.items():
        c[:, CONTROL_NAMES.index(k)] = v
    return c


def _move(lip, base=None, **values):
    base = base or {}
    return (lip.deform(_controls(**{**base, **values})) - lip.deform(_controls(**base))).reshape(2, lip.rows,
                                                                                                 lip.cols, 3)


@pytest.fixture(scope="module")
def lips():
    return {k: LipModel("default", kinematics=k) for k in KINEMATICS}


def test_the_jaw_turns_on_an_arc(lips):
    lip = lips["calibrated"]
    d = _move(lip, jaw=1.0)
    mid = lip.cols // 2
    down_lip, back_lip = -d[1, 0, mid, 1], -d[1, 0, mid, 2]
    down_chin, back_chin = -d[1, -1, mid, 1], -d[1, -1, mid, 2]
    assert down_lip == pytest.approx((1 - 1 / 3) * 18.0, rel=0.02)   # the lower lip's two thirds of the opening
    assert d[0, 0, mid, 1] == pytest.approx(6.0, rel=0.02)             # the upper lip's third
    # down and back; the lower the point (further below the pivot), the more back per mm down
    assert 0.3 < back_lip / down_lip < 0.6 and back_chin / down_chin > back_lip / down_lip + 0.1
    classic = _move(lips["classic"], jaw=1.0)
    assert -classic[1, 0, mid, 2] < 0.1 * -classic[1, 0, mid, 1]      # classic: the lip drops nearly straight


def test_corners_follow_the_jaw_and_narrow_whole(lips):
    lip = lips["calibrated"]
    c = int(np.argmin(np.abs(lip._x - lip._W)))                       # the talker's left corner
    d = _move(lip, jaw=1.0)
    assert 0.25 * 12.0 < -d[0, 0, c, 1] < 0.35 * 12.0      # about 30 % of the lower lip's 12-mm drop
    assert abs(_move(lips["classic"], jaw=1.0)[0, 0, c, 1]) < 0.5   # classic: the corner stays
    out = c + 1 if lip._x[c] < lip._W else c           # beyond the commissure the lips' points coincide
    assert lip._e[out] == 0.0
    np.testing.assert_allclose(d[0, 0, out], d[1, 0, out], atol=0.01)   # ... and the jaw moves them as one
    assert d[0, 0, out, 2] < -1.0                                  # back, with the lower lip
    r = _move(lip, round=1.0)
    rc = _move(lips["classic"], round=1.0)
    assert -r[0, 0, c, 0] > 1.7 * -rc[0, 0, c, 0] > 0                 # in by ~16 % of the half-width, not ~8 %
    assert r[0, 0, c, 2] > rc[0, 0, c, 2] + 1.0                        # and forward over the curved face


def test_jaw_forward_moves_the_chin_only_when_calibrated(lips):
    d = _move(lips["calibrated"], jaw_forward=1.0)
    mid = lips["calibrated"].cols // 2
    assert d[1, -1, mid, 2] == pytest.approx(3.0, rel=0.02) and d[1, 0, mid, 2] == pytest.approx(1.8, rel=0.02)
    assert np.abs(d[0, 1:, mid]).max() < 1e-6                           # the upper lip stays (midline)
    assert np.abs(_move(lips["classic"], jaw_forward=1.0)).max() == 0.0


def test_aperture_stays_exact(lips):
    rng = np.random.default_rng(3)
    C = rng.uniform(0.0, 1.0, (300, len(CONTROL_NAMES)))
    for lip in lips.values():
        P = lip.deform(C).reshape(len(C), -1, 3)
        u, lo = lip.midline
        np.testing.assert_allclose(P[:, u, 1] - P[:, lo, 1], lip.aperture(C), atol=1e-4)


def test_unknown_kinematics_says_the_choices():
    with pytest.raises(ValueError, match="calibrated.*classic.*'bony'"):
        LipModel("small", kinematics="bony")
    with pytest.raises(ValueError, match="kinematics must be one of"):
        SyntheticTalker(preset="small", kinematics="x").generate()


@pytest.fixture(scope="module")
def calibrated_small():
    return SyntheticTalker(preset="small", kinematics="calibrated").generate()


def test_phones_drive_the_jaws_protrusion(calibrated_small):
    c = calibrated_small
    jf = c.latent["jaw_forward"]
    at = {}
    for u in c.utterances:
        for p in u.phones:
            at.setdefault(p.label, []).append(jf[u.start + int(round(0.5 * (p.start + p.end) * c.rate))])
    sib = np.mean(at["s"] + at.get("z", []))
    vel = np.mean(at["k"] + at.get("g", []))
    assert sib > 0.25 and vel < sib - 0.3            # forward for /s z/, back for /k g/


def test_calibrated_sensors_move_more_like_real_lips(small_corpus, calibrated_small, shared_data):
    """The calibration's criterion (each sensor's RMS movement relative to the lower lip's, on
    the real Haskins pair) and a held-out check on MOCHA's midsagittal sensors: the calibrated
    talker's upper-lip and corner ratios are nearer the real speakers' than the classic one's."""
    from engine.io.dispatch import read_corpus

    files = sorted((shared_data / "haskins-ieee").glob("*.mat"))
    mocha = sorted((shared_data / "mocha-fsew0").glob("*.ema"))
    if not files or not mocha:
        pytest.skip("the Haskins pair or the MOCHA recording is not in ../shared/data")
    real = []
    for f in files:
        c = read_corpus(str(f))
        m = sensor_motion(c.frames, [list(c.point_names).index(k) for k in SENSOR_ROLES])
        real.append(m / m[1])
    real = np.mean(real, 0)
    s = virtual_sensors(LipModel("small"))
    pts = [s[k] for k in SENSOR_ROLES]

    def ratios(corpus):
        m = sensor_motion(corpus.frames, pts)
        return m / m[1]

    classic, calibrated = ratios(small_corpus), ratios(calibrated_small)
    for k in ("UL", "ML"):
        i = SENSOR_ROLES.index(k)
        assert abs(calibrated[i] - real[i]) < abs(classic[i] - real[i])
    # held out: MOCHA's UL / LL in the midsagittal plane (2-D), never used to set the kinematics
    c = read_corpus(str(mocha[0]))
    names = list(c.point_names)
    mm = sensor_motion(c.frames, [names.index("UL"), names.index("LL")], dims=2)

    def midsagittal(corpus):
        F = np.asarray(corpus.frames).reshape(corpus.n_frames, -1, 3)[:, [pts[0], pts[1]], 1:]
        m = sensor_motion(F.reshape(len(F), -1), [0, 1], dims=2)
        return m[0] / m[1]

    assert abs(midsagittal(calibrated_small) - mm[0] / mm[1]) < abs(midsagittal(small_corpus) - mm[0] / mm[1])
