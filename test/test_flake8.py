"""ament_flake8 over the package, its tests and benchmarks."""

from conftest import REPO
import pytest


@pytest.mark.linter
def test_flake8():
    main = pytest.importorskip('ament_flake8.main')
    paths = [str(REPO / name) for name in ('hydro_sdp', 'test', 'bench', 'setup.py')]
    rc, errors = main.main_with_errors(argv=paths)
    assert rc == 0, f'found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)
