"""What a design says of the dead-zone edges the data leave undetermined (methods 5.8)."""

from __future__ import annotations

from hydro_sdp.core.model.joint_model import JointModel


def design_notes(model: JointModel) -> tuple[str, ...]:
    """Return one line per undetermined edge: the bound, the value the IDZ takes, and why."""
    rest = model.rest_command
    edges = model.dead_zone or (rest, rest)
    notes = []
    for entry in model.undetermined:
        if not entry.is_edge:
            continue
        value = edges[entry.side]
        notes.append(f'{entry.parameter} is undetermined in [{entry.bound[0]:.4g}, '
                     f"{entry.bound[1]:.4g}]: the IDZ takes the model's {value:.4g}, an "
                     f'extrapolation from {entry.moving_end:.4g} (the innermost command that '
                     f'moved the joint, at {100 * entry.motion:.0f} % of its fastest speed) '
                     'towards rest, where no command was held')
    return tuple(notes)
