"""The first-order recursion in numpy equals scipy's lfilter, over blocks and edge poles."""

from hydro_sdp.core.model.first_order import first_order
import numpy as np
import pytest
from scipy.signal import lfilter


@pytest.mark.parametrize('pole', [0.0, 1e-5, 0.3, 0.9, 0.999, 0.99999, 1.0, -0.5])
@pytest.mark.parametrize('shape', [(1000,), (7, 3000), (2, 40_000)])
def test_first_order_equals_lfilter(rng, pole, shape):
    x = 10.0 * rng.normal(size=shape)
    before = rng.normal(size=shape[:-1]) if len(shape) > 1 else 2.5
    initial = pole * np.asarray(before)
    expected, _ = lfilter([1.0 - pole], [1.0, -pole], x, axis=-1,
                          zi=initial[..., None] if len(shape) > 1 else [initial])
    np.testing.assert_allclose(first_order(x, pole, 1.0 - pole, before), expected,
                               rtol=0.0, atol=1e-11)


def test_a_pole_outside_the_unit_interval_is_refused():
    with pytest.raises(ValueError, match='must lie in'):
        first_order(np.ones(3), 1.5)
