import math

import numpy as np
import pytest

from selector.errors import UnknownIndexError
from selector.indices import (
    INDEX_NAMES,
    column_scale,
    index_from_information,
    observability,
    parse_index,
    scale_columns,
)


def _direct(J: np.ndarray, index: str) -> float:
    """The textbook formulas on a full SVD of the stacked (3m × n) Jacobian."""
    m, n = J.shape[0], J.shape[2]
    s = np.linalg.svd(J.reshape(-1, n), compute_uv=False)
    return {
        "O1": np.prod(s) ** (1.0 / n) / math.sqrt(m),
        "O2": s[-1] / s[0],
        "O3": s[-1],
        "O4": s[-1] ** 2 / s[0],
        "O5": 1.0 / np.sum(1.0 / s),
    }[index]


@pytest.mark.parametrize("index", INDEX_NAMES)
def test_indices_match_direct_svd(blocks: np.ndarray, index: str) -> None:
    J = blocks[:20]
    assert observability(J, index) == pytest.approx(_direct(J, index), rel=1e-10)
    M = J.reshape(-1, J.shape[2]).T @ J.reshape(-1, J.shape[2])
    assert float(index_from_information(M, 20, index)) == pytest.approx(_direct(J, index), rel=1e-8)


def test_o1_ranks_identically_under_any_scaling(blocks: np.ndarray) -> None:
    a, b = blocks[:15], blocks[100:115]
    s = np.random.default_rng(0).uniform(0.01, 100, size=blocks.shape[2])
    ratio = observability(a) / observability(b)
    assert observability(a * s) / observability(b * s) == pytest.approx(ratio, rel=1e-10)
    # O2 is not scale-invariant, which is why the scaling is explicit.
    assert observability(a * s, "O2") != pytest.approx(observability(a, "O2"), rel=1e-3)


def test_rank_deficient_set_scores_zero(blocks: np.ndarray) -> None:
    assert observability(blocks[:2]) == 0.0  # 6 rows for 9 parameters


def test_column_scalings(blocks: np.ndarray) -> None:
    unit = scale_columns(blocks, "unit")
    rms = np.sqrt(np.mean(np.sum(unit**2, axis=1), axis=0))
    assert np.allclose(rms, 1.0)
    expected = np.full(blocks.shape[2], 2.0)
    assert np.allclose(scale_columns(blocks, "expected", expected), 2 * blocks)
    assert np.allclose(column_scale(blocks, "none"), 1.0)
    with pytest.raises(ValueError, match="expected"):
        column_scale(blocks, "expected")
    with pytest.raises(ValueError, match="scaling"):
        column_scale(blocks, "bogus")


def test_parse_index() -> None:
    assert parse_index(" o3 ") == "O3"
    with pytest.raises(UnknownIndexError, match="O1, O2"):
        parse_index("O6")
