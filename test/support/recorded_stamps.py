"""
Bags stamped as a machine stamps them: time since 1970, timer jitter, commands at their own rate.

A plant ticks every ``dt`` and applies the last command that reached it before
the tick; the recorder stamps each sample with a clock reading that wanders by
``jitter`` around the tick, and each command when it arrives, on the
commander's own timer (``command_period``, not in step with the samples, with
its own jitter). Stamps are integer nanoseconds from ``EPOCH`` (1.76e9 s, late
2025), as ``ros2 bag record`` writes them.

The joint itself is any per-sample function of the commands it received (a
model's simulation, the physics plant): :func:`asynchronous_commands` gives the
commands the plant applied at each tick, :func:`write_recorded_bag` writes what
the recorder saw.
"""

from dataclasses import dataclass

from hydro_sdp.bags import Stamped, write_topics
from hydro_sdp.core.model.timing import command_in_force
import numpy as np

#: 2025-10-10 in nanoseconds since 1970: what a wall clock stamps.
EPOCH = 1_760_000_000 * 10 ** 9
#: Timer jitter of a loaded computer, s (uniform +-).
JITTER = 0.5e-3


@dataclass(frozen=True)
class Recording:
    """
    What a recorder on a real machine writes for one joint.

    Attributes
    ----------
    sample_stamps : numpy.ndarray
        Stamp of each sample, ns since 1970 (the ticks plus the clock's jitter).
    command_stamps : numpy.ndarray
        Stamp of each command message, ns since 1970.
    commands : numpy.ndarray
        The command messages.
    applied : numpy.ndarray
        The command the plant applied over the interval ending at each tick.

    """

    sample_stamps: np.ndarray
    command_stamps: np.ndarray
    commands: np.ndarray
    applied: np.ndarray


def asynchronous_commands(program, samples, dt=0.01, *, command_period=0.02,
                          jitter=JITTER, seed=0, epoch=EPOCH):
    """
    Commands sent on their own timer from a program of time, and what the plant applied.

    Parameters
    ----------
    program : callable
        Command as a function of time since the first tick, s (array in, array out).
    samples : int
        Ticks of the plant.
    dt : float
        Plant period, s.
    command_period : float
        Period of the commander's timer, s (its phase is random).
    jitter : float
        Both timers' jitter and the recorder clock's, s (uniform +-).
    seed : int
        Seed.
    epoch : int
        Stamp of the first tick, ns.

    Returns
    -------
    Recording
        Stamps, messages and the per-tick commands.

    """
    rng = np.random.default_rng(seed)
    ticks = np.arange(samples) * dt
    sent = np.arange(-2.0 * command_period + rng.uniform(0.0, command_period),
                     ticks[-1] + command_period, command_period)
    sent = np.sort(sent + rng.uniform(-jitter, jitter, sent.size))
    commands = np.asarray(program(np.maximum(sent, 0.0)), dtype=np.float64)
    to_ns = 1e9
    tick_ns = np.round(ticks * to_ns).astype(np.int64)
    sent_ns = np.round(sent * to_ns).astype(np.int64)
    # The plant sees the true instants; the recorder reads a clock that wanders.
    applied = commands[command_in_force(tick_ns, sent_ns)]
    stamps = tick_ns + np.round(rng.uniform(-jitter, jitter, samples) * to_ns).astype(np.int64)
    return Recording(epoch + stamps, epoch + sent_ns, commands, applied)


def write_recorded_bag(path, recording, joint, angles, *, command_topic=None,
                       storage='sqlite3'):
    """
    Write the recorder's bag: ``/joint_states`` and the commands, each at its own stamps.

    Parameters
    ----------
    path : path-like
        Bag folder.
    recording : Recording
        Stamps and commands (:func:`asynchronous_commands`).
    joint : str
        Joint name.
    angles : numpy.ndarray
        Angle of each sample, degrees.
    command_topic : str or None
        Default ``/<joint>/valve_command``.
    storage : str
        ``sqlite3`` or ``mcap``.

    Returns
    -------
    pathlib.Path
        The bag.

    """
    topic = command_topic or f'/{joint}/valve_command'
    positions = np.radians(np.asarray(angles, dtype=np.float64))[:, None]
    return write_topics(path, recording.sample_stamps, [joint], positions,
                        {topic: Stamped(recording.command_stamps, recording.commands)},
                        storage=storage)


def held_program(times, levels):
    """
    Return a program holding ``levels[i]`` from ``times[i]`` on (the first before it).

    Parameters
    ----------
    times : numpy.ndarray
        Increasing switching times, s.
    levels : numpy.ndarray
        Commands.

    Returns
    -------
    callable
        Command as a function of time.

    """
    times = np.asarray(times, dtype=np.float64)
    levels = np.asarray(levels, dtype=np.float64)

    def program(t):
        index = np.searchsorted(times, np.asarray(t), side='right') - 1
        return levels[np.clip(index, 0, levels.size - 1)]
    return program


def program_of_samples(commands, dt=0.01):
    """Turn a per-sample command sequence (a synthetic program) into a program of time."""
    commands = np.asarray(commands, dtype=np.float64)
    return held_program(np.arange(commands.size) * dt, commands)
