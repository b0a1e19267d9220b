"""
A whole machine in one bag: the physics plant's arm and boom on one pump, from MDF4.

They are logged as a data logger logs them (MDF4, one channel group per rate) and
imported with --signals; diagnose names flow_sharing on the imported bags as on bags
written directly.
"""

from dataclasses import replace

from asammdf import MDF, Signal
from hydro_sdp.bags import write_bag
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.records import Record
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.model_files import save_model
from hydro_sdp.io.plant_files import load_machine
import numpy as np
import pytest
from support.cli_runs import run_json
from support.plant_levels import plant_levels

pytestmark = [pytest.mark.slow, pytest.mark.usefixtures('figures_not_drawn')]

DT = 0.01
SIGNALS = """\
joints:
  arm:  {angle: Arm_ang, command: Arm_out_duty, command_negative: Arm_in_duty}
  boom: {angle: Boom_ang, command: Boom_up_duty, command_negative: Boom_dn_duty}
signals:
  arm/pump_pressure: Pump_P
"""


def write_logger_file(path, commands, angles, seed):
    """Log the run as a logger does: row k's duties are those applied at t_k, on its clock."""
    t = 3600.0 + DT * np.arange(len(commands))
    applied = np.r_[commands[1:], commands[-1:]]
    pump_t = 3600.0 + 0.001 * np.arange(10 * len(commands))
    mdf = MDF(version='4.10')
    mdf.append([Signal(angles[:, 0], t, name='Arm_ang'), Signal(angles[:, 1], t, name='Boom_ang')])
    mdf.append([Signal(np.maximum(applied[:, 0], 0.0), t, name='Arm_out_duty'),
                Signal(np.maximum(-applied[:, 0], 0.0), t, name='Arm_in_duty'),
                Signal(np.maximum(applied[:, 1], 0.0), t, name='Boom_up_duty'),
                Signal(np.maximum(-applied[:, 1], 0.0), t, name='Boom_dn_duty')])
    pump = np.random.default_rng(seed).uniform(100.0, 200.0, pump_t.size)
    mdf.append([Signal(pump, pump_t, name='Pump_P')])
    mdf.save(str(path), overwrite=True)
    mdf.close()
    return path


@pytest.fixture(scope='module')
def machine_runs(tmp_path_factory):
    """Identify the arm with the boom still; log runs with both moving two ways."""
    arm = load_machine(shipped_config('physics_arm.yaml'))
    boom = load_machine(shipped_config('physics_boom.yaml'))
    excavator = replace(arm, joints=(arm.joints[0], boom.joints[0]))
    folder = tmp_path_factory.mktemp('machine')
    alone = []
    # Every run rests a sample before its first command: the log holds what came before it.
    for seed in (1, 2, 3):
        c, a = plant_levels(excavator, DT, 30.0, [0], seed, resting=2)
        alone.append(Record(DT * np.arange(1, len(c) + 1), c[:, 0], a[:, 0], 'arm',
                            f'alone {seed}'))
    model = identify(alone).model
    save_model(model, folder / 'arm.yaml')
    direct, logged = [], []
    for seed in (4, 5):
        c, a = plant_levels(excavator, DT, 30.0, [0, 1], seed, resting=2)
        t = DT * np.arange(1, len(c) + 1)
        records = [Record(t, c[:, j], a[:, j], name) for j, name in enumerate(('arm', 'boom'))]
        direct.append(str(write_bag(folder / 'direct' / f'run{seed}', records)))
        logged.append(str(write_logger_file(folder / f'run{seed}.mf4', c, a, seed)))
    (folder / 'machine.yaml').write_text(SIGNALS)
    imported = run_json('import', *logged, '--out', folder / 'imported', '--signals',
                        folder / 'machine.yaml')
    return folder, direct, imported


def test_the_import_holds_the_machine(machine_runs):
    _, _, imported = machine_runs
    assert imported['joints'] == ['arm', 'boom'] and imported['signals'] == ['/arm/pump_pressure']
    assert imported['samples'] == [3000] * 2


def test_diagnose_names_flow_sharing_on_the_import_as_on_the_direct_bags(machine_runs):
    folder, direct, imported = machine_runs
    found = {}
    for name, bags in (('direct', direct), ('imported', imported['bags'])):
        found[name] = run_json('diagnose', *bags, '--joint', 'arm', '--model',
                               folder / 'arm.yaml', '--iterations', '1')
    assert found['direct']['effect'] == 'flow_sharing'
    assert found['imported']['effect'] == found['direct']['effect']
    # The same records: the same gap, to rounding.
    assert found['imported']['mae_before'] == pytest.approx(found['direct']['mae_before'],
                                                            rel=1e-9)
