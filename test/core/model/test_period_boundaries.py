"""The sample period is checked where it enters, and stays a SamplePeriod inside (methods 3.4)."""

from dataclasses import replace
import math
import pickle

from hydro_sdp import design_from_model, load_controller, Record, save_controller, simulate
from hydro_sdp.core.calibration import CalibrationSettings
from hydro_sdp.core.control.loop_check import CheckSettings
from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.identification.segmentation import check_records
from hydro_sdp.core.model.sample_period import control_period_on
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.core.synthetic.physics import PlantSimulator, simulate_plant
from hydro_sdp.core.synthetic.physics.runs import (
    full_stroke_runs, random_levels, step_and_return)
from hydro_sdp.core.synthetic.programs import random_program, step_program
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.plant_files import load_machine
import numpy as np
import pytest

BAD = [0.0, -0.01, math.nan, math.inf, '0.01']


@pytest.fixture(scope='module')
def boom():
    return load_machine(shipped_config('physics_boom.yaml'))


@pytest.fixture(scope='module')
def spec(j2):
    return design_from_model(j2, control_period=0.05)


#: Every call a period enters the core through, by name: (fixture names, call with the period).
BOUNDARIES = {
    'simulate': lambda j2, **_: lambda dt: simulate(j2, np.zeros(20), dt, 30.0),
    'JointModel.alpha': lambda j2, **_: j2.alpha,
    'JointModel.delay_samples': lambda j2, **_: j2.delay_samples,
    'JointModel.longest_delay_samples': lambda j2, **_: j2.longest_delay_samples,
    'design_from_model': lambda j2, **_: lambda p: design_from_model(j2, control_period=p),
    'ControllerSpec': lambda spec, **_: lambda p: replace(spec, control_period=p),
    'CalibrationSettings': lambda **_: lambda p: CalibrationSettings(control_period=p),
    'CheckSettings': lambda **_: lambda dt: CheckSettings(dt=dt),
    'step_program': lambda j2, **_: lambda dt: step_program(j2, dt),
    'random_program': lambda j2, **_: lambda dt: random_program(j2, dt, 10.0),
    'experiment_record': lambda j2, **_: lambda dt: experiment_record(j2, 'steps', dt=dt),
    'simulate_plant': lambda boom, **_: lambda dt: simulate_plant(boom, np.zeros(5), dt),
    'PlantSimulator': lambda boom, **_: lambda dt: PlantSimulator(boom, dt),
    'full_stroke_runs': lambda boom, **_: lambda dt: full_stroke_runs(boom, dt, [80.0]),
    'step_and_return': lambda boom, **_: lambda dt: step_and_return(boom, dt, [80.0]),
    'random_levels': lambda boom, **_: lambda dt: random_levels(boom, dt, 5.0),
}


@pytest.mark.parametrize('bad', BAD, ids=repr)
@pytest.mark.parametrize('boundary', list(BOUNDARIES))
def test_every_boundary_refuses_a_bad_period_in_one_line(boundary, bad, j2, boom, spec):
    call = BOUNDARIES[boundary](j2=j2, boom=boom, spec=spec)
    with pytest.raises(ConfigurationError) as refused:
        call(bad)
    assert str(refused.value) == f'sample period must be a positive number of seconds, got {bad!r}'


@pytest.mark.parametrize(('value', 'message'), [
    (0.0, "key 'control_period': sample period must be a positive number of seconds, got 0.0"),
    (-0.05, "key 'control_period': sample period must be a positive number of seconds, "
            'got -0.05'),
    ('.nan', "key 'control_period': must be finite, got nan"),
    ("'0.05'", "key 'control_period': expected a number, got str '0.05'"),
], ids=['zero', 'negative', 'nan', 'text'])
def test_a_controller_file_with_a_bad_period_names_the_key(tmp_path, spec, value, message):
    path = save_controller(spec, tmp_path / 'controller.yaml')
    path.write_text(path.read_text().replace('control_period: 0.05',
                                             f'control_period: {value}'))
    with pytest.raises(ModelFileError) as refused:
        load_controller(path)
    assert str(refused.value) == f'{path}: {message}'


def test_the_period_is_carried_as_a_sample_period(spec, tmp_path):
    t = np.arange(1, 201) * 0.01
    record = Record(t, np.zeros(200), np.zeros(200), joint='j2')
    dt = record.sample_period
    assert type(dt) is SamplePeriod and dt == 0.01
    assert type(check_records([record, record], 'analyse')) is SamplePeriod
    # A value already checked is not made again.
    assert SamplePeriod(dt) is dt
    # Arithmetic gives a plain float; a period made from it is wrapped again explicitly.
    assert type(5 * dt) is float and type(dt / 2) is float
    control = control_period_on(0.0499, dt)
    assert type(control.seconds) is SamplePeriod
    assert (control.samples, control.seconds) == (5, 0.05)
    # Numbers given to the boundaries come out checked.
    assert type(spec.control_period) is SamplePeriod
    assert type(CalibrationSettings(control_period=0.1).control_period) is SamplePeriod
    assert type(CheckSettings(dt=0.02).dt) is SamplePeriod
    assert type(pickle.loads(pickle.dumps(dt))) is SamplePeriod
    # Files get a plain number: the controller file round-trips.
    assert type(spec.to_mapping()['control_period']) is float
    again = load_controller(save_controller(spec, tmp_path / 'controller.yaml'))
    assert type(again.control_period) is SamplePeriod and again.control_period == 0.05
