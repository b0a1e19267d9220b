"""mypy over the package with the settings of mypy.ini (every function typed)."""

from conftest import REPO
import pytest


@pytest.mark.linter
@pytest.mark.slow(30)
def test_mypy():
    api = pytest.importorskip('mypy.api')
    stdout, stderr, status = api.run(['--config-file', str(REPO / 'mypy.ini'),
                                      str(REPO / 'hydro_sdp')])
    assert status == 0, f'mypy found errors:\n{stdout}{stderr}'
