"""
The package builds with colcon and ``ros2 run`` would find every executable.

There is no ``ros2`` command line here, so this repeats its lookup: the ament
index marker gives the package prefix, and ``lib/hydro_sdp`` must hold each
console script exactly once, executable (ros2pkg ``get_executable_paths``).

"""

import ast
import configparser
import os
from pathlib import Path
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

from conftest import REPO
import pytest

PACKAGE = 'hydro_sdp'
# rosdep keys of the Python libraries the package imports (ROS packages go by their name).
ROSDEP_KEYS = {'numpy': 'python3-numpy', 'scipy': 'python3-scipy',
               'matplotlib': 'python3-matplotlib', 'yaml': 'python3-yaml',
               'rosbags': 'python3-rosbags-pip', 'h5py': 'python3-h5py',
               'asammdf': 'python3-asammdf-pip'}
# Imported through rclpy.lifecycle, whose services carry its messages.
USED_THROUGH_RCLPY = {'lifecycle_msgs'}


def _colcon():
    found = shutil.which('colcon', path=str(Path(sys.executable).parent)) or shutil.which('colcon')
    if found is None:
        pytest.skip('colcon is not installed')
    return found


@pytest.fixture(scope='module')
def install_prefix(tmp_path_factory):
    workspace = tmp_path_factory.mktemp('workspace')
    result = subprocess.run(
        [_colcon(), '--log-base', str(workspace / 'log'), 'build', '--base-paths', str(REPO),
         '--build-base', str(workspace / 'build'), '--install-base', str(workspace / 'install')],
        cwd=workspace, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    return workspace / 'install' / PACKAGE


def _executables(prefix):
    """List what ``ros2 run`` would consider: executable files under lib/<package>."""
    found = []
    for directory, subdirectories, files in os.walk(prefix / 'lib' / PACKAGE):
        subdirectories[:] = sorted(d for d in subdirectories if not d.startswith('.'))
        for name in sorted(files):
            path = Path(directory) / name
            if os.access(path, os.X_OK):
                found.append(path)
    return found


def _console_scripts(prefix):
    entry_points = next(prefix.glob('lib/python*/site-packages/hydro_sdp*/entry_points.txt'))
    parser = configparser.ConfigParser()
    parser.read(entry_points)
    return dict(parser['console_scripts'])


def test_ament_index_finds_the_package(install_prefix, monkeypatch):
    packages = pytest.importorskip('ament_index_python.packages')
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(install_prefix))
    marker = install_prefix / 'share/ament_index/resource_index/packages' / PACKAGE
    assert marker.is_file()
    assert Path(packages.get_package_prefix(PACKAGE)) == install_prefix
    share = Path(packages.get_package_share_directory(PACKAGE))
    assert (share / 'package.xml').is_file()
    shipped = sorted(p.name for p in (REPO / 'config').glob('*.yaml'))
    assert shipped and sorted(p.name for p in (share / 'config').glob('*.yaml')) == shipped


def test_every_executable_resolves_exactly_once(install_prefix):
    scripts = _console_scripts(install_prefix)
    assert scripts['hydro-sdp'] == 'hydro_sdp.cli.main:entry_point'
    names = [path.name for path in _executables(install_prefix)]
    for name in scripts:
        assert names.count(name) == 1, f'{name} found {names.count(name)} times in lib/{PACKAGE}'
    assert sorted(names) == sorted(scripts)
    assert not (install_prefix / 'bin').exists()


def test_installed_command_runs_and_finds_the_shipped_model(install_prefix, tmp_path):
    site = next(install_prefix.glob('lib/python*/site-packages'))
    environment = dict(os.environ, PYTHONPATH=str(site), AMENT_PREFIX_PATH=str(install_prefix))
    script = install_prefix / 'lib' / PACKAGE / 'hydro-sdp'
    result = subprocess.run(
        [str(script), 'simulate', str(install_prefix / 'share' / PACKAGE / 'config' /
                                      'brokk_j2.yaml'),
         '--program', 'steps', '--duration', '6', '--out', str(tmp_path / 'bag'), '--json'],
        env=environment, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert '"samples"' in result.stdout
    code = ('from hydro_sdp.io.model_files import default_model_path; print(default_model_path())')
    where = subprocess.run([sys.executable, '-c', code], env=environment, cwd=tmp_path,
                           capture_output=True, text=True, timeout=60)
    assert where.stdout.strip() == str(install_prefix / 'share' / PACKAGE / 'config' /
                                       'brokk_j2.yaml')


def test_setup_cfg_uses_underscore_keys():
    # Dashed keys are silently ignored by setuptools inside a virtual environment.
    text = (REPO / 'setup.cfg').read_text()
    assert 'install_scripts=$base/lib/hydro_sdp' in text
    assert 'script_dir=$base/lib/hydro_sdp' in text
    assert '-scripts' not in text and 'script-dir' not in text


def _imported_packages():
    """Return the top-level names the package imports, beyond itself and the standard library."""
    names = set()
    for path in (REPO / PACKAGE).rglob('*.py'):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names.update(alias.name.split('.')[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split('.')[0])
    return names - set(sys.stdlib_module_names) - {PACKAGE}


def test_package_xml_declares_every_package_imported():
    root = ElementTree.parse(REPO / 'package.xml').getroot()
    declared = {element.text for element in root
                if element.tag in ('depend', 'exec_depend', 'build_export_depend')}
    needed = {ROSDEP_KEYS.get(name, name) for name in _imported_packages() | USED_THROUGH_RCLPY}
    assert needed <= declared, f'package.xml does not declare {sorted(needed - declared)}'
    unused = declared - needed
    assert not unused, f'package.xml declares {sorted(unused)}, which nothing imports'
