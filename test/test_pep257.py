"""ament_pep257 docstring checks over the package, its tests and benchmarks."""

from conftest import REPO
import pytest


@pytest.mark.linter
def test_pep257():
    main = pytest.importorskip('ament_pep257.main')
    rc = main.main(argv=[str(REPO / name) for name in ('hydro_sdp', 'test', 'bench', 'setup.py')])
    assert rc == 0, 'found docstring style errors'
