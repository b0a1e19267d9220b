"""Shared fixtures of the hydro_sdp test suite."""

import importlib.util
import os
from pathlib import Path
import sys

from hydro_sdp.io.model_files import default_model_path, load_model
import numpy as np
import pytest
from support.figures import figures_not_drawn as not_drawn

REPO = Path(__file__).resolve().parent.parent
# Real rosbag2 bags (rosbag2's own test resources) live beside the repository, not in it;
# HYDRO_SDP_FIXTURES names another place. Tests that need them skip, saying where they looked.
FIXTURES = Path(os.environ.get('HYDRO_SDP_FIXTURES')
                or REPO.parent / 'shared' / 'data' / 'rosbag2_fixtures')

# pytest rewrites the asserts of every test module in every worker; with
# PYTHONDONTWRITEBYTECODE set (as on CI) it would not keep the result, and each of the three
# workers would rewrite the suite again (5 s of CPU each). The package's own bytecode is
# compiled before the run (make test).
sys.dont_write_bytecode = False

# The ROS tests need rclpy; without it they are left out (test_ros_available reports a skip).
collect_ignore_glob = [] if importlib.util.find_spec('rclpy') else ['ros/*']


def pytest_xdist_auto_num_workers(config):
    """
    Run one test worker more than there are cores (``-n auto`` in pytest.ini).

    A third of the suite's time is spent waiting (node processes discovering each other,
    recordings on the wall clock, a scene's ``sleep``): a worker more keeps the cores busy.
    """
    return len(os.sched_getaffinity(0)) + 1


def pytest_collection_modifyitems(items):
    """
    Start the longest modules first, so that the test workers end together.

    xdist hands out whole modules (``--dist loadfile``) in the collection's order
    (``--no-loadscope-reorder``); a module that starts last and runs long would run alone
    at the end. A ``slow`` mark may say how many seconds its module takes
    (``pytest.mark.slow(120)``); a plain one counts 10, a module without one nothing.
    The order within a module is kept.
    """
    def seconds(item):
        mark = item.get_closest_marker('slow')
        return 0.0 if mark is None else float(mark.args[0]) if mark.args else 10.0
    cost = {}
    for item in items:
        cost[item.path] = max(cost.get(item.path, 0.0), seconds(item))
    items.sort(key=lambda item: -cost[item.path])


@pytest.fixture
def rng():
    """Return a seeded random generator, one per test."""
    return np.random.default_rng(20260101)


@pytest.fixture(scope='session')
def j2():
    """Load the shipped BROKK J2 model."""
    return load_model(default_model_path())


@pytest.fixture(scope='module')
def figures_not_drawn():
    """
    Write the module's figures as blank PNGs (``support.figures``).

    For modules that test what commands compute: ``pytestmark =
    pytest.mark.usefixtures('figures_not_drawn')`` sets it up before their other fixtures.
    """
    with not_drawn():
        yield
