"""Trajectory files: joint angles over time (YAML or CSV), or a straight tip line (YAML)."""

from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path

from hydro_sdp.core.control.kinematics import line_trajectory, TwoLinkArm
from hydro_sdp.core.control.trajectory import JointTrajectory
from hydro_sdp.core.errors import DataError, ModelFileError
from hydro_sdp.core.validation import (
    Document, read_document, require_float, require_mapping, require_pair)
from hydro_sdp.io.documents import load_yaml, shipped_config
import numpy as np

TRAJECTORY_FORMAT = 'hydro_sdp/trajectory/v1'


@dataclass(frozen=True, eq=False)
class TrajectoryFile:
    """
    What a trajectory file asks for.

    Attributes
    ----------
    trajectory : JointTrajectory
        The joint trajectory (for a line: dense points on it).
    line : tuple of two (x, z) points or None
        Ends of the tip line, m.

    """

    trajectory: JointTrajectory
    arm: TwoLinkArm | None = None
    line: tuple[tuple[float, float], tuple[float, float]] | None = None


def load_kinematics(path: str | os.PathLike[str]) -> TwoLinkArm:
    """Load a kinematics file (``hydro_sdp/kinematics/v1``); errors name the file and the key."""
    data = load_yaml(path)
    try:
        return TwoLinkArm.from_mapping(data)
    except ModelFileError as error:
        raise ModelFileError(f'{path}: {error}') from None


def load_trajectory(path: str | os.PathLike[str],
                    kinematics: str | os.PathLike[str] | None = None) -> TrajectoryFile:
    """Load a trajectory file, YAML or CSV (by its suffix ``.csv``)."""
    source = Path(path)
    try:
        if source.suffix.lower() == '.csv':
            return TrajectoryFile(_from_csv(source))
        return _from_yaml(source, load_yaml(source), kinematics)
    except (ModelFileError, DataError) as error:
        raise ModelFileError(f'{source}: {error}') from None


def _from_csv(source: Path) -> JointTrajectory:
    try:
        text = source.read_text(encoding='utf-8')
    except FileNotFoundError:
        raise ModelFileError('no such file') from None
    except (OSError, UnicodeDecodeError) as error:
        raise ModelFileError(f'cannot read: {error}') from None
    rows = [(number, line) for number, line in enumerate(text.splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith('#')]
    if not rows:
        raise ModelFileError('no header and no points')
    header = [cell.strip() for cell in rows[0][1].split(',')]
    if len(header) < 2 or header[0] != 'time':
        raise ModelFileError(f"line {rows[0][0]}: the header must be 'time,<joint>,...', "
                             f'got {rows[0][1]!r}')
    times, positions = [], []
    for number, line in rows[1:]:
        cells = line.split(',')
        if len(cells) != len(header):
            raise ModelFileError(f'line {number}: expected {len(header)} values, '
                                 f'got {len(cells)}')
        try:
            values = [float(cell) for cell in cells]
        except ValueError:
            raise ModelFileError(f'line {number}: not numbers: {line!r}') from None
        times.append(values[0])
        positions.append(values[1:])
    if not times:
        raise ModelFileError('no points after the header')
    return JointTrajectory(tuple(header[1:]), np.array(times), np.array(positions))


def _from_yaml(source: Path, data: object,
               kinematics: str | os.PathLike[str] | None) -> TrajectoryFile:
    data = read_document(data, 'a trajectory file', TRAJECTORY_FORMAT,
                         known=('format', 'joint_names', 'points', 'kinematics', 'line'))
    if 'line' in data:
        for key in ('joint_names', 'points'):
            if key in data:
                raise ModelFileError(f"key {key!r} does not go with 'line'")
        return _line(source, data, kinematics)
    for key in ('joint_names', 'points'):
        if key not in data:
            raise ModelFileError(f"missing required key {key!r} (or give 'line')")
    names = data['joint_names']
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise ModelFileError("key 'joint_names': expected a list of joint names")
    points = data['points']
    if not isinstance(points, list) or not points:
        raise ModelFileError("key 'points': expected a list of points")
    times, positions, velocities = [], [], []
    for index, point in enumerate(points):
        where = f'points[{index}]'
        point = require_mapping(point, where, ('time_from_start', 'positions', 'velocities'),
                                ('time_from_start', 'positions'), expected='a mapping')
        times.append(require_float(point['time_from_start'], f'{where}.time_from_start'))
        positions.append(_numbers(point['positions'], f'{where}.positions', len(names)))
        if 'velocities' in point:
            velocities.append(_numbers(point['velocities'], f'{where}.velocities', len(names)))
    if velocities and len(velocities) != len(points):
        raise ModelFileError('velocities must be given in every point or in none')
    return TrajectoryFile(JointTrajectory(tuple(names), np.array(times), np.array(positions),
                                          np.array(velocities) if velocities else None))


def _numbers(value: object, key: str, count: int) -> list[float]:
    if not isinstance(value, list) or len(value) != count:
        raise ModelFileError(f'key {key!r}: expected a list of {count} numbers '
                             '(one per joint)')
    return [require_float(item, f'{key}[{i}]') for i, item in enumerate(value)]


def _line(source: Path, data: Document,
          kinematics: str | os.PathLike[str] | None) -> TrajectoryFile:
    line = require_mapping(data['line'], 'line',
                           ('start', 'end', 'speed', 'duration', 'point_period', 'elbow'),
                           ('start', 'end'),
                           expected='a mapping with start, end and speed or duration')
    start, end = require_pair(line['start'], 'line.start'), require_pair(line['end'], 'line.end')
    timing = {key: require_float(line[key], f'line.{key}')
              for key in ('speed', 'duration', 'point_period') if key in line}
    if ('speed' in timing) == ('duration' in timing):
        raise ModelFileError("key 'line': give speed (m/s) or duration (s), one of them")
    if kinematics is None:
        name = data.get('kinematics')
        if not isinstance(name, str):
            raise ModelFileError("missing required key 'kinematics' (a kinematics file)")
        beside = source.parent / name
        kinematics = beside if beside.is_file() or Path(name).is_absolute() else None
        if kinematics is None:
            try:
                kinematics = shipped_config(name)
            except FileNotFoundError:
                raise ModelFileError(f"key 'kinematics': no file {name!r} beside the "
                                     'trajectory file nor among the shipped ones') from None
    arm = load_kinematics(kinematics)
    trajectory = line_trajectory(arm, start, end, speed=timing.get('speed'),
                                 duration=timing.get('duration'),
                                 point_period=timing.get('point_period', 0.05),
                                 elbow=str(line.get('elbow', 'up')))
    return TrajectoryFile(trajectory, arm, (start, end))
