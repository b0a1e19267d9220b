"""The forms of ``load_dependence`` with a measured load, per direction (methods 8.2)."""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

from hydro_sdp.core.diagnosis.residuals import MIN_GAIN, Run
from hydro_sdp.core.identification.held_out import WindowErrors
from hydro_sdp.core.model.effects import LoadDependence
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np


def one_side(effect: LoadDependence, positive: bool) -> LoadDependence:
    """Return ``effect`` with the other direction left alone (factor 1)."""
    ones = (1.0,) * len(effect.knots)
    if positive:
        return replace(effect, negative=0.0, overrun_negative=0.0, onset_negative=0.0,
                       factors_negative=ones, limit_negative=0.0, limit_offset_negative=0.0)
    return replace(effect, positive=0.0, overrun_positive=0.0, onset_positive=0.0,
                   factors_positive=ones, limit_positive=0.0, limit_offset_positive=0.0)


def joined(up: LoadDependence | None, down: LoadDependence | None) -> LoadDependence | None:
    """Return the positive direction of ``up`` with the negative of ``down`` (None: neither)."""
    if up is None:
        return None if down is None else one_side(down, False)
    if down is None:
        return one_side(up, True)
    knots = up.knots or down.knots
    return replace(up, negative=down.negative, overrun_negative=down.overrun_negative,
                   onset_negative=down.onset_negative, limit_negative=down.limit_negative,
                   limit_offset_negative=down.limit_offset_negative, knots=knots,
                   factors_positive=up.factors_positive or (1.0,) * len(knots),
                   factors_negative=down.factors_negative or (1.0,) * len(knots))


def best_sides(base: JointModel, forms: Sequence[LoadDependence],
               runs: Sequence[Run]) -> tuple[LoadDependence | None, tuple[int, int]]:
    """
    Choose each direction's form by the windowed simulation error on ``runs``.

    Returns: the effect joined from the chosen directions (None: no form helps either), and the
    index in ``forms`` of each direction's form (-1: none).
    """
    errors = WindowErrors(runs)
    chosen: list[int] = []
    up: LoadDependence | None = None
    for positive in (True, False):
        trials = [one_side(form, positive) for form in forms]
        made = [joined(up, trial) if not positive else trial for trial in trials]
        models = [base if up is None else base.with_effect(one_side(up, True))]
        models += [base.with_effect(effect) for effect in made if effect is not None]
        scores = errors.compare(models)
        best = int(np.argmin(scores))
        if best > 1 and scores[best] > (1.0 - MIN_GAIN) * scores[1]:
            best = 1 if scores[1] < scores[0] else 0
        chosen.append(best - 1)
        if positive and best > 0:
            up = forms[best - 1]
    effect = joined(up, forms[chosen[1]] if chosen[1] >= 0 else None)
    return effect, (chosen[0], chosen[1])
