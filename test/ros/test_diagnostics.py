"""/diagnostics of the controller node: one status per joint, OK, WARN, ERROR."""

import math

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import Lockstep, RosHarness
from outside import ARM, CONTROLLER, MODELS, Processes
import pytest
from std_msgs.msg import Float64

pytestmark = pytest.mark.ros

JOINTS = ['boom', 'dipper']
OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


@pytest.fixture
def ros():
    """Return a harness with its own context, closed after the test."""
    with RosHarness() as harness:
        yield harness


def _by_joint(array):
    return {status.hardware_id: status for status in array.status}


def test_one_status_per_joint_each_second_and_an_error_when_feedback_stops(ros):
    plant = ros.add(PlantNode, parameters={'model_files': MODELS})
    controller = ros.add(PipControllerNode, parameters={'joints': JOINTS, 'model_files': MODELS})
    reports = []
    ros.helper('diagnostics').create_subscription(DiagnosticArray, '/diagnostics',
                                                  reports.append, 10)
    loop = Lockstep(ros, plant, controllers=[controller])
    loop.run(150)                                               # 1.5 s: one report
    assert ros.spin_until(lambda: len(reports) == 1)
    statuses = _by_joint(reports[0])
    assert sorted(statuses) == JOINTS
    boom = statuses['boom']
    assert boom.name == 'pip_controller: boom' and boom.level == OK and boom.message == 'ok'
    values = {kv.key: kv.value for kv in boom.values}
    assert float(values['set-point [deg]']) == 0.0 and float(values['feedback age [s]']) <= 0.01
    assert float(values['IDZ lower edge']) == controller.loop('boom').spec.idz.dead_zone[0]
    # A set-point beyond the end stops is clamped: a warning for that joint only.
    setpoint = ros.helper('setpoint').create_publisher(Float64, 'boom/setpoint', 10)
    count = controller.setpoints_received
    ros.send(setpoint, Float64(data=math.radians(90.0)),
             lambda: controller.setpoints_received > count)
    loop.run(100)
    assert ros.spin_until(lambda: len(reports) == 2)
    statuses = _by_joint(reports[1])
    assert statuses['boom'].level == WARN and 'clamped' in statuses['boom'].message
    assert statuses['dipper'].level == OK
    # The plant falls silent: the watchdog closes both valves, the report says ERROR.
    ros.executor.remove_node(plant)
    for k in range(1, 161):                                     # 2.5 s to 4.1 s
        step = loop.steps + k
        ros.set_time(step * 10**7)
        ros.spin_for(0.002)
        if step % 100 == 0:
            # Each whole second's report is taken before the clock moves on: on a loaded
            # machine a 2 ms spin may not reach its timer, which then reports a later age.
            assert ros.spin_until(lambda: len(reports) == step // 100)
    assert ros.spin_until(lambda: len(reports) == 4)
    # At 3 s the silence is 0.5 s (feedback_timeout): stale; at 4 s the valves are closed.
    assert all(s.level == WARN and 'feedback stale (0.500 s old)' in s.message
               for s in reports[2].status)
    statuses = _by_joint(reports[3])
    for joint in JOINTS:
        assert statuses[joint].level == ERROR
        assert statuses[joint].message.startswith('watchdog closed the valve')


@pytest.mark.slow
def test_diagnostics_of_a_controller_process_go_to_error_when_the_plant_stops(monkeypatch):
    nodes = Processes(monkeypatch, ('plant_node', ARM), ('controller_node', CONTROLLER))
    try:
        reports = []
        nodes.node.create_subscription(DiagnosticArray, '/diagnostics', reports.append, 10)
        assert nodes.spin_until(
            lambda: reports and all(s.level == OK for s in reports[-1].status), 30.0), \
            nodes.died()
        assert sorted(_by_joint(reports[-1])) == JOINTS
        nodes.stop('plant_node')
        count = len(reports)
        assert nodes.spin_until(lambda: len(reports) > count and all(
            s.level == ERROR for s in reports[-1].status), 5.0)
    finally:
        nodes.close()


def test_the_identifier_reports_estimates_and_a_needed_recalibration(ros):
    from hydro_sdp.ros.identifier_node import IdentifierNode
    from test_multi_joint import _ShiftedEstimator
    plant = ros.add(PlantNode, parameters={'model_files': MODELS})
    controller = ros.add(PipControllerNode, parameters={'joints': JOINTS, 'model_files': MODELS})
    identifier = ros.add(IdentifierNode, parameters={
        'joints': JOINTS, 'model_files': MODELS, 'settle': 0.5})
    dipper = identifier.item('dipper')
    dipper.estimator = _ShiftedEstimator(dipper.model, (-40.0, 35.0))
    reports = []
    ros.helper('diagnostics').create_subscription(DiagnosticArray, '/diagnostics',
                                                  reports.append, 10)
    loop = Lockstep(ros, plant, controllers=[controller], observers=[identifier])
    loop.run(250)
    assert ros.spin_until(lambda: sum(
        r.status[0].name.startswith('sdp_identifier') for r in reports) == 2)
    last = [r for r in reports if r.status[0].name.startswith('sdp_identifier')][-1]
    statuses = _by_joint(last)
    assert statuses['boom'].level == OK
    assert statuses['dipper'].name == 'sdp_identifier: dipper'
    assert (statuses['dipper'].level, statuses['dipper'].message) == (
        WARN, 'recalibration needed')
    values = {kv.key: kv.value for kv in statuses['dipper'].values}
    assert values['dead_zone_lower [input units]'] == '-40'
    assert values['dead_zone_lower [input units] std'] == '1'
    assert values['IDZ lower edge'] == '-60'          # what the controller still uses
