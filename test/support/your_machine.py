"""
Stand-ins for the recordings and logs that the user guide's "your machine" examples name.

A boom driven in percent duty resting at 50 % on ``/boom/pwm`` (steps and an operator's
run, as bags ``bag_recorder`` would write), an arm with a signed duty logged by four
kinds of logger (CSV, MDF4, MATLAB, a dSPACE ControlDesk export in CP949), and a day's
logs of both joints with the boom's head pressure (MDF4). The joints are
``support.plain_joint`` joints, not the package's simulator; stamps run on the loggers'
own clocks.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from asammdf import MDF, Signal
from hydro_sdp.bags import write_bag
import numpy as np
from scipy.io import savemat
from support.controldesk_files import Trace, write_controldesk
from support.plain_joint import PlainJoint, steps

#: The boom: a valve in percent duty resting at 50 %, end stops at -40 and 55 deg.
BOOM = PlainJoint(delay=10, dead_zone=(43.0, 56.0), slope=(1.6, 2.0), saturation=(30.0, 36.0),
                  stops=(-40.0, 55.0))
#: The arm: a signed duty, -100..100 %.
ARM = PlainJoint(delay=8, dead_zone=(-12.0, 10.0), slope=(0.8, 1.0), saturation=(28.0, 34.0),
                 stops=(-50.0, 60.0))
#: The day's boom, logged as two one-sided duties.
DAY_BOOM = PlainJoint(delay=12, dead_zone=(-15.0, 14.0), slope=(0.7, 0.9),
                      saturation=(22.0, 26.0), stops=(-30.0, 50.0))


def _boom_bags(folder: Path) -> None:
    for index, levels in enumerate(([20.0, -20.0, 30.0, -30.0, 45.0, -40.0],
                                    [12.0, -12.0, 25.0, -25.0, 35.0, -35.0])):
        record = BOOM.run(50.0 + steps(levels, hold=1.5, rest=0.8), seed=index)
        write_bag(folder / 'step_bags' / f'steps_{index + 1}', [replace(record, joint='boom')],
                  command_topics={'boom': '/boom/pwm'})
    run = BOOM.run_joystick(30.0, neutral=50.0, reach=45.0, seed=5)
    write_bag(folder / 'random_bags' / 'run_1', [replace(run, joint='boom')],
              command_topics={'boom': '/boom/pwm'})


def _arm_logs(folder: Path) -> None:
    for name, seed in (('fit_1', 1), ('fit_2', 2), ('check_1', 3)):
        run = ARM.run_levels(20.0, magnitude=(15.0, 90.0), seed=seed)
        t = run.t - run.t[0]
        rows = '\n'.join(f'{a:.3f},{b:.5f},{c:.2f}' for a, b, c in zip(t, run.y, run.v))
        (folder / f'{name}.csv').write_text(f'logger 7, channel list v2\nt,arm_deg,duty\n{rows}\n')
    run = ARM.run_levels(20.0, magnitude=(15.0, 90.0), seed=4)
    t = run.t - run.t[0]
    mdf = MDF(version='4.10')
    mdf.append([Signal(run.y, t, name='Arm_ang'), Signal(run.v, t, name='Arm_duty')])
    mdf.save(str(folder / 'run1.mf4'), overwrite=True)
    mdf.close()
    run = ARM.run_levels(20.0, magnitude=(15.0, 90.0), seed=6)
    savemat(folder / 'run2.mat', {'t': (run.t - run.t[0])[:, None],
                                  'log': {'Arm_ang': run.y[:, None], 'Arm_duty': run.v[:, None]}})
    run = ARM.run_levels(10.0, magnitude=(15.0, 90.0), seed=7)
    write_controldesk(folder / 'arm_cd_1.csv', [(np.arange(len(run)) * 0.0099909, [
        Trace('In1', 'Model Root/Arm/Arm_ang/In1', 'deg', run.y),
        Trace('Out1', 'Model Root/Valves/Arm_duty/Out1', '%', run.v)])])


def _day_logs(folder: Path) -> None:
    (folder / 'day1').mkdir()
    for index in (1, 2):
        arm = ARM.run_levels(30.0, magnitude=(15.0, 90.0), seed=10 + index)
        boom = DAY_BOOM.run_levels(30.0, magnitude=(20.0, 90.0), seed=20 + index)
        t = arm.t - arm.t[0]
        pressure = 80.0 + 40.0 * np.sin(0.3 * t + index)
        mdf = MDF(version='4.10')
        mdf.append([Signal(arm.y, t, name='Arm_ang'), Signal(boom.y, t, name='Boom_ang')])
        mdf.append([Signal(np.maximum(arm.v, 0.0), t, name='Arm_out_duty'),
                    Signal(np.maximum(-arm.v, 0.0), t, name='Arm_in_duty'),
                    Signal(np.maximum(boom.v, 0.0), t, name='Boom_up_duty'),
                    Signal(np.maximum(-boom.v, 0.0), t, name='Boom_dn_duty'),
                    Signal(pressure, t, name='Boom_head_P')])
        mdf.save(str(folder / 'day1' / f'log_{index}.mf4'), overwrite=True)
        mdf.close()


def write_your_machine(folder: Path) -> None:
    """Write every recording and log of the guide's "your machine" examples into ``folder``."""
    _boom_bags(folder)
    _arm_logs(folder)
    _day_logs(folder)
