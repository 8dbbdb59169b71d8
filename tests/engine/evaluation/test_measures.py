import numpy as np
import pytest

from engine.evaluation.measures import trajectory_errors, trajectory_y


def test_trajectories_in_y(small_manifold):
    from engine.manifold.model import project_x
    from engine.phonetics.targets import targets_from_utterance
    from engine.synthesis.viterbi import InterpolationSynthesizer, Trajectory, ViterbiSynthesizer

    m = small_manifold
    u = m.corpus_.utterances[1]
    F = m.corpus_.frames[u.start:u.stop]
    # X -> Y is the manifold's own out-of-sample pipeline minus its shape stage
    np.testing.assert_allclose(project_x(m, m.shape_.transform(F)), m.project(F), rtol=1e-4, atol=1e-3)
    # a training utterance's own X projects onto its in-sample F^y (velocities inside the utterance)
    np.testing.assert_allclose(project_x(m, m.Fx_[u.start:u.stop]), m.Fy_[u.start:u.stop], rtol=1e-3,
                               atol=1e-3 * float(np.abs(m.Fy_).max()))
    tg = targets_from_utterance(m, u.id)
    man = ViterbiSynthesizer().fit(m).synthesize(tg)
    Ym = trajectory_y(m, man)
    assert Ym.shape == (u.n_frames, 3)
    np.testing.assert_allclose(Ym, m.states_.centroids_[man.states][:, :3], rtol=1e-6)  # before the inverse map
    lin = InterpolationSynthesizer(kind="linear").fit(m).synthesize(tg)
    np.testing.assert_allclose(trajectory_y(m, lin), project_x(m, lin.Fx)[:, :3], rtol=1e-6)
    # states clustered in fewer dims than scored: each state's mean F^y stands in
    lab = m.states_.labels_
    two = Trajectory(times=man.times, Fx=man.Fx, Fy=man.Fy[:, :2], method="manifold", states=man.states)
    means = np.stack([m.Fy_[lab == k, :3].mean(0) for k in man.states])
    np.testing.assert_allclose(trajectory_y(m, two), means, rtol=1e-4, atol=1e-4)


def test_trajectory_errors_of_the_real_trajectory_are_the_reconstruction_error(small_manifold):
    m = small_manifold
    u = m.corpus_.utterances[0]
    F = m.corpus_.frames[u.start:u.stop]
    own = trajectory_errors(m, m.Fx_[u.start:u.stop], F)
    assert own["rmse_x"] == pytest.approx(0.0, abs=1e-3 * float(np.abs(m.Fx_).max()))
    resid = np.linalg.norm((m.shape_.inverse_transform(m.Fx_[u.start:u.stop]) - F).reshape(len(F), -1, 3), axis=2)
    assert own["mean_point_error"] == pytest.approx(resid.mean(), rel=1e-4)
    shifted = m.Fx_[u.start:u.stop] + np.eye(m.Fx_.shape[1], dtype=np.float32)[0] * 2.0
    assert trajectory_errors(m, shifted, F)["rmse_x"] == pytest.approx(2.0, rel=1e-3)
