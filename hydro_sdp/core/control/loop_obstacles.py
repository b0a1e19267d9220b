"""What stands in the way of a failed closed-loop check (methods 10)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Sequence

from hydro_sdp.core.control.controller_spec import ControllerSpec
from hydro_sdp.core.control.design_plant import completed_poles, mode_poles, plant_for_model
from hydro_sdp.core.control.idz_table import TableInverseDeadZone
from hydro_sdp.core.control.loop_check import check_loop, CheckSettings, LoopCheck
from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import PwlMap, SdpDzMap, StaticMap
import numpy as np

#: The elements, in the order they are tried.
ELEMENTS = ('map', 'delay', 'lag', 'noise', 'effects')

#: Design of a controller for an idealised model: ``redesign(model, poles)``.
Redesign = Callable[[JointModel, Sequence[complex]], ControllerSpec]


@dataclass(frozen=True)
class Obstacle:
    """
    The check with one element idealised.

    Attributes
    ----------
    element : str
        One of :data:`ELEMENTS`.

    """

    element: str
    idealised: str
    passed: bool
    failures: int


def exact_map(spec: ControllerSpec) -> StaticMap | None:
    """Return the map the controller's IDZ inverts exactly (deg/s), or ``None`` without IDZ."""
    idz, period = spec.idz, spec.control_period
    if idz is None:
        return None
    if isinstance(idz, TableInverseDeadZone):
        return PwlMap(knots=idz.v, speeds=tuple(u / period for u in idz.u))
    if idz.dead_zone[0] == idz.dead_zone[1] and idz.slopes[0] == idz.slopes[1]:
        return None           # a linear map inverted by its gain: nothing to idealise
    return SdpDzMap(dead_zone=idz.dead_zone,
                    slope=(idz.slopes[0] / period, idz.slopes[1] / period))


def dominant_poles(spec: ControllerSpec) -> list[complex]:
    """Return the spec's two slowest poles (an exactly conjugate pair if complex), not a mode's."""
    mode = () if spec.oscillation is None else mode_poles(spec.oscillation, spec.control_period)
    poles = sorted((complex(p) for p in spec.poles
                    if not any(abs(complex(p) - m) < 0.05 for m in mode)),
                   key=abs, reverse=True)[:2]
    if len(poles) == 2 and poles[0].imag != 0.0:
        poles = [poles[0], poles[0].conjugate()]
    return poles


def _idealised(model: JointModel, spec: ControllerSpec,
               settings: CheckSettings) -> list[tuple[str, str, JointModel, bool, CheckSettings]]:
    """Return ``(element, words, model, redesign?, settings)`` for each element that applies."""
    cases = []
    exact = exact_map(spec)
    if exact is not None:
        cases.append(('map', 'the map the IDZ inverts', replace(model, static_map=exact),
                      False, settings))
    if model.delay_samples(spec.control_period) > 1:
        cases.append(('delay', 'one control sample',
                      replace(model, delay=spec.control_period), True, settings))
    if model.effect(ValveLag.name) is not None:
        cases.append(('lag', 'none', model.without_effect(ValveLag.name), True, settings))
    if settings.noise_std > 0.0:
        cases.append(('noise', 'none', model, False, replace(settings, noise_std=0.0)))
    others = [effect.name for effect in model.effects if effect.name != ValveLag.name]
    if others:
        bare = model
        for name in others:
            bare = bare.without_effect(name)
        cases.append(('effects', f'without {", ".join(others)}', bare, False, settings))
    return cases


def obstacles(model: JointModel, spec: ControllerSpec, stroke: tuple[float, float],
              settings: CheckSettings, redesign: Redesign) -> tuple[Obstacle, ...]:
    """
    Run the check with each element idealised in turn.

    ``stroke``: the check's stroke, degrees.
    ``settings``: the check's settings (noise included).
    ``redesign``: designs the controller for an idealised model with given poles (the same IDZ form
    and options as ``spec``).
    Returns: one per element that applies, in the order of :data:`ELEMENTS`.
    """
    found = []
    for element, words, ideal, again, ideal_settings in _idealised(model, spec, settings):
        controller = spec
        if again:
            plant = plant_for_model(ideal, spec.control_period)
            try:
                controller = redesign(ideal, completed_poles(plant, dominant_poles(spec)))
            except HydroSdpError:
                continue
        check: LoopCheck = check_loop(ideal, controller, stroke, settings=ideal_settings)
        found.append(Obstacle(element, words, check.passed, len(check.failures)))
    return tuple(found)


def standing_in_the_way(found: Sequence[Obstacle], failures: int) -> tuple[str, ...]:
    """Return the elements that stand in the way of a check that failed ``failures`` ways."""
    passing = tuple(o.element for o in found if o.passed)
    if passing or not found:
        return passing
    fewest = int(np.min([o.failures for o in found]))
    if fewest >= failures:
        return ()
    return tuple(o.element for o in found if o.failures == fewest)
