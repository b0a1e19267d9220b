"""The unit of a joint's command, for axis labels and reports."""

from __future__ import annotations

from hydro_sdp.core.model.joint_model import JointModel

#: Input ranges whose unit is clear: percent duty, and the +-10 V of a valve amplifier.
KNOWN_RANGES: dict[tuple[float, float], str] = {
    (0.0, 100.0): '%', (-100.0, 100.0): '%', (-10.0, 10.0): 'V', (0.0, 10.0): 'V'}
#: Label when nothing says what the unit is.
UNKNOWN_UNIT = 'input units'


def command_unit_of(model: JointModel | tuple[float, float] | None,
                    given: str | None = None) -> str:
    """
    Return the label of a joint's command unit.

    ``model``: the joint, or its input limits.
    ``given``: the unit the user named; wins when given.
    Returns: ``given``; else ``%`` for input limits [0, 100] or [-100, 100], ``V`` for [-10, 10] or
    [0, 10]; else ``input units``.
    """
    if given:
        return given
    limits = model.input_limits if isinstance(model, JointModel) else model
    if limits is None:
        return UNKNOWN_UNIT
    return KNOWN_RANGES.get((float(limits[0]), float(limits[1])), UNKNOWN_UNIT)
