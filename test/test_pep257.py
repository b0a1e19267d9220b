"""ament_pep257 docstring checks over the package."""

from conftest import REPO
import pytest


@pytest.mark.linter
def test_pep257():
    main = pytest.importorskip('ament_pep257.main')
    rc = main.main(argv=[str(REPO / 'hydro_sdp'), str(REPO / 'bench')])
    assert rc == 0, 'found docstring style errors'
