import numpy as np
import pytest

from selector.information import DesignState, det3, information, inv3


def _logdet(M: np.ndarray) -> float:
    sign, value = np.linalg.slogdet(M)
    return value if sign > 0 else -np.inf


def test_det3_inv3_match_lapack() -> None:
    A = np.random.default_rng(1).normal(size=(50, 3, 3))
    assert np.allclose(det3(A), np.linalg.det(A))
    assert np.allclose(inv3(A), np.linalg.inv(A))


def test_low_rank_scores_match_recomputation(blocks: np.ndarray) -> None:
    G = blocks
    state = DesignState(G, np.arange(12))
    base = _logdet(information(G, state.chosen))
    assert state.logdet == pytest.approx(base, rel=1e-12)
    cands = np.arange(50, 70)
    add = state.add_gain(cands)
    for k, c in enumerate(cands):
        assert add[k] == pytest.approx(_logdet(state.M + G[c].T @ G[c]) - base, abs=1e-9)
    loss = state.remove_loss()
    for i, c in enumerate(state.chosen):
        assert loss[i] == pytest.approx(_logdet(state.M - G[c].T @ G[c]) - base, abs=1e-9)
    swap = state.swap_gain(cands)
    for k, c in enumerate(cands):
        for i, old in enumerate(state.chosen):
            ref = _logdet(state.M + G[c].T @ G[c] - G[old].T @ G[old]) - base
            assert swap[k, i] == pytest.approx(ref, abs=1e-9)
    d = state.variance(cands)
    Minv = np.linalg.inv(state.M)
    assert np.allclose(d, [np.trace(G[c] @ Minv @ G[c].T) for c in cands])


def test_swap_updates_the_state(blocks: np.ndarray) -> None:
    state = DesignState(blocks, np.arange(12))
    predicted = state.logdet + state.swap_gain(np.array([99]))[0, 4]
    out = state.swap(4, 99)
    assert out == 4 and state.chosen[4] == 99 and state.in_set[99] and not state.in_set[4]
    assert state.logdet == pytest.approx(predicted, abs=1e-9)
    assert state.logdet == pytest.approx(_logdet(information(blocks, state.chosen)), abs=1e-9)
    with pytest.raises(ValueError, match="already"):
        state.swap(0, 99)


def test_singular_start_is_flagged(blocks: np.ndarray) -> None:
    state = DesignState(blocks, np.arange(2))  # 6 rows, 9 parameters
    assert state.logdet == -np.inf
    assert np.all(np.isfinite(state.add_gain(np.arange(10, 20))))
