"""Valve commands taken from the one allowed source, within the valve's range and rate."""

from hydro_sdp.core.control.command_gate import CommandGate
from hydro_sdp.core.errors import ConfigurationError, DataError
import pytest

MS = 1_000_000


def test_any_one_node_is_taken_and_two_close_the_valve():
    gate = CommandGate((-10.0, 10.0))
    assert gate.admit(2.5, 0, ['/pip_controller']) == 2.5
    assert gate.admit(25.0, 10 * MS, ['/pip_controller']) == 10.0       # clamped
    with pytest.raises(DataError, match=r"2 publishers \['/intruder', '/pip_controller'\]: "
                                        'a valve takes commands from one node'):
        gate.admit(10.0, 20 * MS, ['/pip_controller', '/intruder'])
    with pytest.raises(DataError, match='0 publishers'):
        gate.admit(1.0, 30 * MS, [])          # the graph does not know the sender yet
    with pytest.raises(DataError, match='not finite'):
        gate.admit(float('nan'), 40 * MS, ['/pip_controller'])


def test_a_named_source_is_the_only_one_taken():
    gate = CommandGate(None, source='/arm/pip_controller')
    assert gate.admit(1e6, 0, ['/arm/pip_controller']) == 1e6       # no range: as given
    for publishers in (['/pip_controller'], ['/arm/pip_controller', '/bag_player'], []):
        with pytest.raises(DataError, match='only /arm/pip_controller may command this valve'):
            gate.admit(1.0, 0, publishers)


def test_commands_beyond_the_rate_are_dropped_after_a_burst():
    gate = CommandGate(None, rate_limit=100.0, burst=3)
    taken = [gate.admit(1.0, k * MS, ['/c']) for k in range(6)]       # 1 kHz for 6 ms
    assert taken == [1.0, 1.0, 1.0, None, None, None]
    assert gate.admit(2.0, 16 * MS, ['/c']) == 2.0                  # 10 ms: one more token
    # A controller at 20 Hz is never limited.
    steady = CommandGate(None, rate_limit=100.0, burst=3)
    assert all(steady.admit(0.5, k * 50 * MS, ['/c']) == 0.5 for k in range(100))


def test_a_silent_source_closes_the_valve_after_the_timeout():
    gate = CommandGate(None, timeout_ns=500 * MS)
    assert not gate.silent(10**12)                 # nothing taken yet: nothing to close
    gate.admit(3.0, 1000 * MS, ['/c'])
    assert not gate.silent(1500 * MS) and gate.silent(1501 * MS)
    assert not CommandGate(None).silent(10**15)    # timeout 0: never
    with pytest.raises(ConfigurationError):
        CommandGate(None, rate_limit=0.0)
