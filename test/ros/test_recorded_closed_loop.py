"""
``identify`` on a recorded closed-loop session: routine operation over DDS, not experiments.

``plant_node`` (J2, 100 Hz, noise 0.02 deg, on the wall clock), ``controller_node`` (its
PIP-IDZ controller, commands at 20 Hz) and ``bag_recorder`` run as three processes in a
fresh ROS domain; an outside client stands in for the operator and moves the set-point
three times (+20, -26, +52 deg), as the user guide's "Recording and replaying" does. No
level is held: the command changes every control period. ``identify`` must take the
routine route and recover J2's dead-zone within 0.1 V and its delay of 0.15 s, and the
controller designed from that model must run the true joint.
"""

import json
import math

from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros import qos
from outside import Processes
import pytest
from std_msgs.msg import Float64
from support.cli_runs import run_cli

pytestmark = [pytest.mark.ros, pytest.mark.slow]

#: The operator's set-points, deg (moves of +20, -26, +52), each held HOLD s.
SETPOINTS = (20.0, -6.0, 46.0)
HOLD = 4.5


@pytest.fixture(scope='module')
def session(tmp_path_factory):
    """Record the session; return the bag's folder."""
    folder = tmp_path_factory.mktemp('closed_loop_session')
    bag = folder / 'rec'
    monkeypatch = pytest.MonkeyPatch()
    nodes = Processes(monkeypatch, ('plant_node', ['-p', 'noise_std:=0.02']),
                      ('controller_node', []),
                      ('bag_recorder', ['-p', f'output:={bag}', '-p', "joint_names:=['j2']"]))
    try:
        setpoint = nodes.node.create_publisher(Float64, 'j2/setpoint', qos.COMMAND_QOS)
        # The controller and the recorder listen, and the recorder has found the topics
        # (it looks for them every discovery_period).
        assert nodes.spin_until(lambda: setpoint.get_subscription_count() >= 2, 60.0), \
            nodes.died()
        nodes.spin_for(2.0)
        for angle in SETPOINTS:
            setpoint.publish(Float64(data=math.radians(angle)))
            nodes.spin_for(HOLD)
        nodes.stop('bag_recorder')
    finally:
        nodes.close()
        monkeypatch.undo()
    return folder


def test_identify_recovers_the_dead_zone_from_a_recorded_closed_loop(session):
    truth = load_model(default_model_path())
    result = json.loads(run_cli('identify', session / 'rec', '--out', session / 'model.yaml',
                                '--json'))
    assert result['route'] == 'routine'
    assert result['delay'] == pytest.approx(0.15, abs=0.011)
    # The loop's IDZ jumps across the dead-zone, so an edge is pinned or bounded: a point
    # within 0.1 V of the truth, or a bound that holds it (a map family without edges
    # bounds both; methods.md section 13.9).
    edges = result.get('dead_zone') or [None, None]
    for side, true in enumerate(truth.dead_zone):
        bound = result['undetermined'].get(f'dead_zone[{side}]')
        if bound is None:
            assert abs(edges[side] - true) < 0.1, result['dead_zone']
        else:
            low, high = bound['bound']
            assert low - 0.1 < true < high + 0.1, bound
    low, high = truth.dead_zone
    # The valve range is what the loop used, well inside the valve's +-10 V.
    assert result['input_limits_from'] == 'data'
    assert result['input_limits'] == result['commands_seen']
    assert -10.0 < result['input_limits'][0] < low and high < result['input_limits'][1] < 10.0
    assert result['end_stops_from'] == 'none'
    # The chain goes on: a controller from this model runs the true joint (valve +-10 V).
    run_cli('design', session / 'model.yaml', '--out', session / 'controller.yaml')
    loop = json.loads(run_cli('closed-loop', default_model_path(), '--controller',
                              session / 'controller.yaml', '--setpoints', '20', '-6',
                              '--out', session / 'loop', '--json'))
    assert loop['settling_time'] < 4.0 and loop['overshoot'] < 10.0
