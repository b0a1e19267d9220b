"""The nodes start without importing what they do not use (start-up time, issue 14)."""

import os
from pathlib import Path
import subprocess
import sys

import pytest

REPO = Path(__file__).resolve().parents[2]
HEAVY = ('scipy', 'matplotlib', 'rosbags')


def _heavy_modules_after(code: str) -> set[str]:
    """Run ``code`` in a fresh interpreter; return the heavy modules it imported."""
    environment = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(REPO)] + [p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]))
    report = f'import sys\nprint(*(m for m in sys.modules if m.split(".")[0] in {HEAVY!r}))'
    result = subprocess.run([sys.executable, '-c', f'{code}\n{report}'], env=environment,
                            capture_output=True, text=True, timeout=120, check=True)
    return set(result.stdout.split())


@pytest.mark.parametrize('module', ['hydro_sdp.ros.plant_node', 'hydro_sdp.ros.controller_node'])
def test_node_modules_import_no_scipy_matplotlib_or_rosbags(module):
    assert _heavy_modules_after(f'import {module}') == set()


def test_plant_node_construction_imports_no_scipy():
    # The plant simulates sample by sample; scipy (seconds to import) is for offline work.
    code = '\n'.join([
        'import rclpy',
        'from rclpy.context import Context',
        'from hydro_sdp.ros.plant_node import PlantNode',
        'context = Context()',
        'rclpy.init(context=context, domain_id=231)',
        'PlantNode(context=context, start_parameter_services=False).destroy_node()',
        'rclpy.try_shutdown(context=context)'])
    assert _heavy_modules_after(code) == set()


def test_the_probe_sees_an_import():
    # The check above would pass vacuously if the report were broken.
    assert 'scipy.signal' in _heavy_modules_after('import hydro_sdp.core.identification.riv')
