"""
``calibrate`` on a bag that ``bag_recorder`` recorded over DDS, as the user guide records one.

``plant_node`` (J2, 100 Hz, on the wall clock) and ``bag_recorder`` run as two processes
in a fresh ROS domain; an outside client steps the valve open loop on its own 50 Hz
timer, not in step with the plant. The bag is stamped since 1970 with the timers'
jitter; calibrate must read the plant's period as 0.01 s, the delay as 15 samples
(written 0.15; 16 where the host was too busy to pass a command on within a sample), the
plant's map, and pass its closed-loop check.
"""

from contextlib import redirect_stdout
import io
import json
import time

from hydro_sdp.bags import read_bag
from hydro_sdp.cli.main import main
from hydro_sdp.io.model_files import default_model_path, load_model
import numpy as np
from outside import Processes
import pytest
from std_msgs.msg import Float64

pytestmark = [pytest.mark.ros, pytest.mark.slow, pytest.mark.usefixtures('figures_not_drawn')]

#: Steps from rest, volts, each held HOLD s (up) or HOLD_DOWN s (down), then REST s at rest.
LEVELS = (2.0, -2.0, 3.0, -3.0, 1.6, -1.6, 5.0, -5.0, 2.5, -2.5, 1.8, -1.8)
#: J2 runs up about 1.3 times as fast as down: holding the steps down that much longer
#: keeps the joint between 0 and 50 deg, clear of its stops at -13.8 and 63.6 deg. (A stop
#: met only while the delayed command still drives the joint, after the command is back at
#: rest, is not detected as a stop; the joint here stays clear of that case.)
HOLD, HOLD_DOWN, REST = 1.0, 1.3, 0.8
COMMAND_PERIOD = 0.02


def test_calibrate_reads_a_bag_recorded_over_dds(monkeypatch, tmp_path):
    bag = tmp_path / 'rec'
    nodes = Processes(monkeypatch, ('plant_node', ['-p', 'noise_std:=0.02']),
                      ('bag_recorder', ['-p', f'output:={bag}', '-p', "joint_names:=['j2']"]))
    try:
        valve = nodes.node.create_publisher(Float64, 'j2/valve_command', 10)
        # Both the plant and the recorder listen, and the recorder has had time to find
        # joint_states (it looks for topics every discovery_period).
        assert nodes.spin_until(lambda: valve.get_subscription_count() >= 2, 60.0), \
            nodes.died()
        nodes.spin_for(3.0)
        program = [step for level in LEVELS
                   for step in ((level, HOLD if level > 0 else HOLD_DOWN), (0.0, REST))]
        for level, hold in program:
            end = time.monotonic() + hold
            while time.monotonic() < end:
                valve.publish(Float64(data=level))
                nodes.spin_for(COMMAND_PERIOD)
        nodes.stop('bag_recorder')
    finally:
        nodes.close()
    data = read_bag(bag)
    assert data.start > 1.7e18             # stamped with the wall clock
    out = tmp_path / 'cal'
    stdout = io.StringIO()
    with redirect_stdout(stdout):
        code = main(['calibrate', str(bag), '--out', str(out), '--json'])
    assert code == 0
    result = json.loads(stdout.getvalue())
    model = load_model(result['model'])
    # The plant's 15 samples, or one more: on a busy host the plant may take a command a
    # sample after the recorder stamps it, and that time is the recording's delay too (one
    # recording in a run beside two CPU hogs gave 0.16). Transport never makes it shorter.
    assert model.delay in (0.15, 0.16), model.delay
    # The map is the plant's: at every level of the program the model's speed is within
    # 8 % of J2's (seven recordings on a busy machine: 0.6 to 5.2 %, the larger ones up at
    # 2 to 2.5 V). Which effects come with it is not asserted here: over DDS on a busy
    # machine the plant takes a command up to tens of ms after the recorder stamps it,
    # and on about one recording in eight that timing is fitted as valve_lag or
    # stroke_geometry; test_recorded_stamps holds "no effect the plant lacks" on epoch
    # stamps and timer jitter without the scheduler's part.
    levels = np.array(LEVELS)
    true = load_model(default_model_path())
    found, want = model.static_map.rate(levels), true.static_map.rate(levels)
    assert np.all(np.abs(found / want - 1.0) < 0.08), (levels, found, want)
    assert result['closed_loop']['passed']
    params = (out / 'params.yaml').read_text()
    assert 'sample_period' not in params      # the nodes' default 0.01 s: nothing to say
