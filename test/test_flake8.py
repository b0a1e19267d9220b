"""
ament_flake8 over the package, its tests and benchmarks.

Docstrings are test_pep257's: with flake8-docstrings installed, flake8 would run pydocstyle
over the same files a second time.
"""

import subprocess
import sys

from conftest import REPO
import pytest

# In a process of its own: flake8 forks worker processes, and a fork of this test
# process, which has run ROS nodes and their middleware threads, can crash in the child.
RUN = """
import sys
from ament_flake8.main import main_with_errors
rc, errors = main_with_errors(argv=sys.argv[1:])
print('\\n'.join(errors))
sys.exit(rc)
"""


@pytest.mark.linter
@pytest.mark.slow(30)
def test_flake8():
    pytest.importorskip('ament_flake8.main')
    paths = [str(REPO / name) for name in ('hydro_sdp', 'test', 'bench', 'setup.py')]
    done = subprocess.run([sys.executable, '-c', RUN, *paths], capture_output=True, text=True,
                          timeout=300)
    errors = [line for line in done.stdout.splitlines() if line.strip()]
    assert done.returncode == 0, \
        f'found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)
