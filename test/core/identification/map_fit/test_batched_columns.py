"""A Jacobian's columns in one pass give the same numbers, and the same fit, bit for bit."""

from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.identification.map_fit import FitData
from hydro_sdp.core.identification.map_fit.columns import BatchedResiduals, forward_jacobian
from hydro_sdp.core.model.static_maps import sdp_rate
import numpy as np
import pytest
from scipy.optimize import least_squares

TRUTH = (-20.0, 1.5, -1.0, 25.0, 2.0, 0.8)


def _experiments(rng):
    # Uneven lengths (buckets padded unevenly), starts after the first sample, and runs
    # long enough that the lag's and beta's recursions run in several blocks.
    # Every other one commands one side of rest only.
    out = []
    sides = ([-3.0, -1.5, 0.0], [0.0, 2.0, 4.0], [-3.0, -1.5, 0.0, 2.0, 4.0])
    for index, (length, start) in enumerate(
            [(40, 0), (57, 3), (300, 0), (130, 2), (9, 7), (1500, 0), (1400, 5), (1700, 1)]):
        v = np.repeat(rng.choice(sides[index % 3], length // 10 + 1), 10)[:length]
        y = np.cumsum(rng.normal(0.0, 0.05, length)) + 0.01 * np.cumsum(sdp_rate(v, *TRUTH))
        out.append(Experiment(v, y, start, 'step', float(v[-1]), 0.0))
    return out


def _parametrised(x):
    values = tuple(float(value) for value in x[:6])
    return (lambda v: sdp_rate(v, *values)), x[6]


def _free(p):
    # Unbounded, as Levenberg-Marquardt needs: logs of the magnitudes, a logit of beta.
    signs = np.array([-1.0, 1.0, -1.0, 1.0, 1.0, 1.0])
    return _parametrised(np.r_[signs * np.exp(p[:6]), 1.0 / (1.0 + np.exp(-p[6]))])


@pytest.fixture(scope='module', params=[(0.0, False), (0.01, True)], ids=['plain', 'lag+gains'])
def data(request):
    rng = np.random.default_rng(7)
    experiments = _experiments(rng)
    lag, with_gains = request.param
    gains = [rng.uniform(0.5, 1.5, e.y.size - e.start - 1) for e in experiments] \
        if with_gains else None
    return FitData(experiments, 4, 0.01, lag, gains)


def test_many_maps_at_once_equal_one_at_a_time_bit_for_bit(data):
    rng = np.random.default_rng(3)
    points = [np.r_[np.array(TRUTH) * rng.uniform(0.8, 1.2, 6), beta]
              for beta in (0.0, -0.0, 0.4, 0.4, 0.4 + 1e-9, 0.9, 0.0)]
    together = data.residuals_of_many([_parametrised(p) for p in points])
    for point, residuals in zip(points, together):
        alone = data.residuals(*_parametrised(point))
        assert residuals.tobytes() == alone.tobytes()


@pytest.mark.parametrize('method', ['trf', 'lm'])
def test_least_squares_with_batched_columns_is_the_same_fit(data, method):
    if method == 'trf':
        parametrised, x0 = _parametrised, np.r_[np.array(TRUTH) * 1.1, 0.5]
        options = {'bounds': (np.r_[-100.0, 0.1, -3.0, 0.0, 0.1, 0.0, 0.0],
                              np.r_[0.0, 10.0, 0.0, 100.0, 10.0, 3.0, 1.0]),
                   'x_scale': 'jac', 'tr_solver': 'lsmr'}
    else:
        parametrised, x0 = _free, np.r_[np.log(np.abs(TRUTH)) + 0.1, 0.0]
        options = {'method': 'lm'}
    calls = []

    def one_at_a_time(x):
        calls.append(1)
        return data.residuals(*parametrised(x))
    # Levenberg-Marquardt's trial steps may go wild: both runs take the same ones.
    with np.errstate(over='ignore', invalid='ignore'):
        plain = least_squares(one_at_a_time, x0, **options)
    batched = BatchedResiduals(data, parametrised)
    maps = []
    original = data.evaluate

    def counted(items, base=None):
        maps.append(len(items))
        return original(items, base)
    data.evaluate = counted
    try:
        with np.errstate(over='ignore', invalid='ignore'):
            fast = least_squares(batched, x0, workers=batched.map_points, **options)
    finally:
        del data.evaluate
    assert fast.x.tobytes() == plain.x.tobytes()
    assert np.asarray(fast.jac).tobytes() == np.asarray(plain.jac).tobytes()
    assert (fast.cost, fast.nfev, fast.status) == (plain.cost, plain.nfev, plain.status)
    # Every Jacobian went through in one pass of all seven columns.
    assert max(maps) == 7 and len(maps) < len(calls) / 3


def test_residuals_kept_from_a_base_are_those_computed_afresh(data):
    # Moving the negative side's parameters leaves the experiments that never command
    # below rest alone: those keep the base's residuals; every other row is recomputed.
    rng = np.random.default_rng(5)
    x = np.r_[np.array(TRUTH), 0.4]
    base = data.evaluate([_parametrised(x)])[0]
    points = []
    for i in range(x.size):
        moved = x.copy()
        moved[i] *= 1.0 + 1e-7
        points.append(moved)
    points.append(np.r_[np.array(TRUTH) * rng.uniform(0.8, 1.2, 6), 0.4])   # all rates move
    points.append(x.copy())                                                 # none moves
    kept = data.evaluate([_parametrised(p) for p in points], base)
    for point, evaluation in zip(points, kept):
        alone = data.residuals(*_parametrised(point))
        assert evaluation.residuals.tobytes() == alone.tobytes()
    # A base of another beta is not used, and gives the same numbers too.
    other = data.evaluate([_parametrised(x)], data.evaluate([_parametrised(np.r_[x[:6], 0.0])])[0])
    assert other[0].residuals.tobytes() == base.residuals.tobytes()


def test_forward_jacobian_moves_one_parameter_at_a_time(data):
    x = np.r_[np.array(TRUTH), 0.0]
    jacobian = forward_jacobian(data, _parametrised, x)
    base = data.residuals(*_parametrised(x))
    for i in range(x.size):
        step = 1e-6 * max(abs(x[i]), 1e-3)
        shifted = x.copy()
        shifted[i] += step
        column = (data.residuals(*_parametrised(shifted)) - base) / step
        assert jacobian[:, i].tobytes() == column.tobytes()


def test_an_older_scipy_fits_one_column_at_a_time(data, monkeypatch):
    # The pinned scipy takes ``workers``; one without it (a distribution's older package)
    # is given no such argument, and fits as the plain run above does.
    from hydro_sdp.core.identification.map_fit import columns
    batched = BatchedResiduals(data, _parametrised)
    assert columns.TAKES_WORKERS and batched.options == {'workers': batched.map_points}
    monkeypatch.setattr(columns, 'TAKES_WORKERS', False)
    assert batched.options == {}
