"""Grey relational analysis (pydem/seed001/gra.py) against a hand-worked 2-parameter, 3-case table, and its
limits: a parameter that follows the response exactly has every coefficient 1."""
import numpy as np
import pytest

from pydem.seed001.gra import grey_relational


def test_hand_worked_table():
    # y = (2, 4, 6) -> y' = (1, 2, 3); a = (1, 2, 2) -> a' = (1, 2, 2); b = (4, 4, 8) -> b' = (1, 1, 2)
    # |y' - a'| = (0, 0, 1), |y' - b'| = (0, 1, 1); min = 0, max = 1, rho = 0.5:
    # xi_a = (0.5/0.5, 0.5/0.5, 0.5/1.5) = (1, 1, 1/3) -> r_a = 7/9; xi_b = (1, 1/3, 1/3) -> r_b = 5/9
    grades, weights = grey_relational([[1, 2, 2], [4, 4, 8]], [2, 4, 6])
    assert grades == pytest.approx([7 / 9, 5 / 9], rel=1e-15)
    assert weights == pytest.approx([100 * 7 / 12, 100 * 5 / 12], rel=1e-14)


def test_a_parameter_proportional_to_the_response_scores_one():
    rng = np.random.default_rng(0)
    y = rng.uniform(1, 2, 25)
    x = np.vstack([3.0 * y, rng.uniform(1, 2, 25), rng.uniform(1, 2, 25)])
    grades, weights = grey_relational(x, y)
    assert grades[0] == 1.0 and grades[1:].max() < 1.0 and weights.sum() == pytest.approx(100.0)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="reference"):
        grey_relational([[0, 1]], [1, 2])
    with pytest.raises(ValueError, match="rho"):
        grey_relational([[1, 1]], [1, 2], rho=2.0)
    with pytest.raises(ValueError, match="parameters, cases"):
        grey_relational([1, 2], [1, 2])
