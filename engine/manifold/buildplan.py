"""Build plan: which embedding and K-means path a corpus of N frames takes.

One ``lipspace build`` serves every corpus size. The exact embedding (PCA of the full
N x N distance matrix, block-wise) costs O(N^2) distance evaluations per pass; its CPU
time grows with N^1.8-1.9 and at 100,000 frames it is about 155 s against 5-6 CPU-s
for L = 2,000 landmarks, whose F^y correlates with the exact one at ``|r| >= 0.9989``.
So the exact path is taken while ``N <= landmarks_above`` (default 50,000 frames) and
the landmark (Nystrom / landmark-MDS) path above it, with :data:`DEFAULT_LANDMARKS`
landmarks; an explicit ``n_landmarks`` always wins. K-means for the states switches
to mini-batch K-means above ``engine.graph.states.MINIBATCH_ABOVE`` frames.

Memory of the landmark path is O(N (2m + L_block)) + O(L^2): linear in N.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BuildPlan", "plan_build", "LANDMARKS_ABOVE", "DEFAULT_LANDMARKS"]

#: above this many frames the embedding uses landmarks unless told otherwise
LANDMARKS_ABOVE = 50_000
#: landmarks used when the size alone chooses the landmark path
DEFAULT_LANDMARKS = 2_000


@dataclass(frozen=True)
class BuildPlan:
    """The paths a build takes.

    Attributes
    ----------
    n_frames : int
    n_landmarks : int or None
        None: the exact N x N embedding; else the number of landmark frames.
    reason : str
        Why (forced by the caller, or the size against the threshold).
    minibatch_kmeans : bool
        Whether the states use mini-batch K-means.
    """

    n_frames: int
    n_landmarks: int | None
    reason: str
    minibatch_kmeans: bool

    def describe(self) -> str:
        """One line for the command line, e.g. ``embedding: landmark (L=2000) ...``."""
        emb = ("exact block-wise N x N" if self.n_landmarks is None
               else f"landmark (Nystrom, L={self.n_landmarks})")
        km = "mini-batch K-means" if self.minibatch_kmeans else "K-means"
        return f"{self.n_frames} frames: embedding {emb} ({self.reason}); states by {km}"


def plan_build(n_frames: int, *, n_landmarks=None, landmarks_above: int = LANDMARKS_ABOVE,
               default_landmarks: int = DEFAULT_LANDMARKS) -> BuildPlan:
    """Choose the embedding and K-means paths for ``n_frames`` frames.

    Parameters
    ----------
    n_frames : int
        N, the frames of the corpus.
    n_landmarks : int or None
        Forced landmark count (``--landmarks L``); None lets the size decide.
    landmarks_above : int, default=LANDMARKS_ABOVE
        The exact path is used while ``n_frames <= landmarks_above``.
    default_landmarks : int, default=DEFAULT_LANDMARKS
        L when the size chooses landmarks (capped at N).

    Returns
    -------
    BuildPlan
    """
    from engine.graph.states import MINIBATCH_ABOVE

    N = int(n_frames)
    if N < 1:
        raise ValueError(f"n_frames must be >= 1, got {n_frames}")
    if not isinstance(landmarks_above, (int,)) or isinstance(landmarks_above, bool) or landmarks_above < 1:
        raise ValueError(f"landmarks_above must be a positive integer number of frames, got {landmarks_above!r}")
    if n_landmarks is not None:
        L, reason = int(n_landmarks), "--landmarks given"
    elif N > landmarks_above:
        L = int(min(default_landmarks, N))
        reason = f"N > {landmarks_above} frames"
    else:
        L, reason = None, f"N <= {landmarks_above} frames"
    return BuildPlan(n_frames=N, n_landmarks=L, reason=reason, minibatch_kmeans=N > MINIBATCH_ABOVE)
