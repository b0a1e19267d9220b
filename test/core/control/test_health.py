"""The /diagnostics rule of a joint: levels, messages and key-values from a snapshot."""

from hydro_sdp.core.control.health import ERROR, joint_health, JointSnapshot, OK, WARN


def _snapshot(**changes):
    values = {'joint': 'boom', 'feedback_age': 0.01, 'stale_after': 0.25, 'setpoint': 20.0,
              'angle': 19.5, 'command': 120.0, 'idz_edges': (-90.0, 80.0)}
    values.update(changes)
    return JointSnapshot(**values)


def test_a_fed_joint_is_ok_with_its_numbers():
    status = joint_health(_snapshot())
    assert status.level == OK and status.message == 'ok'
    assert dict(status.values) == {
        'active': 'true', 'feedback age [s]': '0.01', 'set-point [deg]': '20',
        'angle [deg]': '19.5', 'error [deg]': '0.5', 'command': '120',
        'IDZ lower edge': '-90', 'IDZ upper edge': '80'}


def test_the_watchdog_is_an_error_whatever_else_holds():
    status = joint_health(_snapshot(watchdog_closed=True, feedback_age=0.73, clamped=True))
    assert status.level == ERROR
    assert status.message == 'watchdog closed the valve: no valid feedback for 0.73 s'


def test_warnings_are_listed_together():
    status = joint_health(_snapshot(feedback_age=0.3, refused=4, clamped=True,
                                    recalibration_needed=True))
    assert status.level == WARN
    assert status.message == ('feedback stale (0.300 s old); feedback refused (4 samples); '
                              'recalibration needed; set-point clamped to the end stops')
    assert joint_health(_snapshot(feedback_age=None)).message == 'no feedback yet'
    assert joint_health(_snapshot(feedback_age=0.25)).level == OK     # at the limit: fresh


def test_an_inactive_node_is_ok_and_says_so():
    status = joint_health(_snapshot(active=False, watchdog_closed=True, refused=3))
    assert (status.level, status.message) == (OK, 'inactive')
    assert ('active', 'false') in status.values


def test_estimates_and_their_std_follow_the_loop_values():
    status = joint_health(_snapshot(setpoint=None, idz_edges=None, estimates={
        'dead_zone_lower': (-1.25, 0.0125), 'delay [s]': (0.1, 0.0)}))
    assert status.values[-4:] == (('dead_zone_lower', '-1.25'), ('dead_zone_lower std', '0.0125'),
                                  ('delay [s]', '0.1'), ('delay [s] std', '0'))
    assert ('error [deg]', 'none') in status.values
    assert not any(key.startswith('IDZ') for key, _ in status.values)
