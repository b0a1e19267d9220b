"""What a design says of the dead-zone edges the data leave undetermined (methods 13.9)."""

from __future__ import annotations

from hydro_sdp.core.model.joint_model import JointModel


def design_notes(model: JointModel, edges: tuple[float, float]) -> tuple[str, ...]:
    """Return one line per undetermined edge: the bound, the IDZ's ``edges``, and why."""
    notes = []
    for entry in model.undetermined:
        if not entry.is_edge:
            continue
        value = edges[entry.side]
        notes.append(f'{entry.parameter} is undetermined in [{entry.bound[0]:.4g}, '
                     f"{entry.bound[1]:.4g}]: the IDZ takes {value:.4g}, where the model's "
                     f'map reaches 0, an extrapolation from {entry.moving_end:.4g} (the '
                     f'innermost command that moved the joint, at {100 * entry.motion:.0f} % '
                     'of its fastest speed) '
                     'towards rest, where no command was held')
    return tuple(notes)
