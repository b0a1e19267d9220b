"""
The effects ``identify`` proposes by itself: checked on held-out experiments, then fitted.

The reasoning is in docs/methods.md section 13.8.

"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable, Sequence

from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.identification.change_windows import (
    ChangeWindows, fit_delay_lag_and_pure, lag_pole)
from hydro_sdp.core.identification.delay import DelayEstimate
from hydro_sdp.core.identification.effect_check import (
    compared, held_out, HeldOut, simulation_errors)
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.identification.family_choice import folds
from hydro_sdp.core.identification.map_fit import FitData, MapFit
from hydro_sdp.core.identification.stroke_fit import fit_stroke_geometry, speed_gains
from hydro_sdp.core.model.effects import StrokeGeometry
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import StaticMap
from hydro_sdp.core.model.timing import SamplePeriod

#: The stroke factor refitted with the map is kept when it lowers the simulation error of
#: the experiments by this share at least (after its held-out check).
GEOMETRY_GAIN = 0.05
#: Alternations of map and stroke factor.
GEOMETRY_ROUNDS = 3

#: Refits the chosen map family to data whose speeds carry known gains.
MapRefit = Callable[[FitData], MapFit[StaticMap]]


def check_lag(experiments: Sequence[Experiment], delay: DelayEstimate, dt: SamplePeriod,
              rest: float, max_delay: int, windows: ChangeWindows | None = None) -> HeldOut:
    """
    Held-out angle error around the command changes, with the lag and with the best pure delay.

    The reasoning is in docs/methods.md section 13.8.

    ``delay``: the delay and lag fitted on all experiments (its lag is what is checked).
    ``dt``: sample period, s.
    ``max_delay``: largest dead time, samples.
    ``windows``: change windows of these experiments or more, fitted already for the delay.
    """
    rows, weights = [], []
    every = ChangeWindows(experiments, max_delay) if windows is None else \
        windows.part(experiments, max_delay)
    for train, test in folds(experiments, rest):
        windows = every.part(test)
        if windows.windows == 0 or delay.lag <= 0.0:
            continue
        try:
            dead, lag, _, pure = fit_delay_lag_and_pure(train, dt, max_delay, every.part(train))
        except HydroSdpError:
            continue
        before, samples = windows.angle_error(pure, 0.0)
        after = windows.angle_error(dead, lag_pole(lag, dt))[0] if lag > 0.0 else before
        rows.append((before / samples, after / samples))
        weights.append(float(samples))
    return compared('valve_lag', rows, weights)


def check_geometry(experiments: Sequence[Experiment], model: JointModel, delay: DelayEstimate,
                   dt: SamplePeriod, stops: tuple[float | None, float | None],
                   reach: float) -> HeldOut:
    """
    Held-out errors of the model without and with a stroke factor fitted on each training part.

    ``model``: the model without the factor (its map fitted on all experiments).
    ``dt``: sample period, s.
    ``stops``: end stops seen, degrees.
    ``reach``: how near a stop counts as at it, degrees.
    """
    def shaped(train: Sequence[Experiment]) -> JointModel | None:
        geometry = fit_stroke_geometry(train, model.static_map.rate, delay.samples, dt,
                                       delay.lag, stops, reach)
        return None if geometry is None else replace(model, effects=model.effects + (geometry,))
    return held_out('stroke_geometry', folds(experiments, model.rest_command),
                    lambda train: model, shaped, dt)


def _mae(model: JointModel, experiments: Sequence[Experiment], dt: SamplePeriod) -> float:
    total, count = simulation_errors(model, experiments, dt)
    return total / max(count, 1)


def shape_with_geometry(model: JointModel, geometry: StrokeGeometry | None, refit_map: MapRefit,
                        first: MapFit[StaticMap], pieces: Sequence[Experiment],
                        sample: Sequence[Experiment], delay: DelayEstimate, dt: SamplePeriod,
                        stops: tuple[float | None, float | None], reach: float
                        ) -> tuple[JointModel | None, MapFit[StaticMap]]:
    """
    Refit the map under the stroke factor, then the factor under the new map, in turn.

    ``geometry``: the factor fitted under the model's map.
    ``refit_map``: refits the chosen map family to data with known gains on the speed.
    ``first``: the fit of the chosen map family without the factor.
    ``pieces``, ``sample``: all experiments, and the (thinned) ones the factor is fitted on.
    ``dt``: sample period, s.
    ``stops``: end stops seen, degrees.
    ``reach``: how near a stop counts as at it, degrees.
    Returns: ``(model, fit)``: the shaped model (None when it gains too little) and the map fit
    under the factor.
    """
    refit = first
    for _ in range(GEOMETRY_ROUNDS):
        if geometry is None:
            break
        # The factor is taken at the measured angles: known gains on the speed.
        refit = refit_map(FitData(pieces, delay.samples, dt, delay.lag, speed_gains(
            pieces, refit.static_map.rate, delay.samples, dt, delay.lag, geometry)))
        geometry = fit_stroke_geometry(sample, refit.static_map.rate, delay.samples, dt,
                                       delay.lag, stops, reach)
    if geometry is None:
        return None, refit
    shaped = replace(model, static_map=refit.static_map, effects=model.effects + (geometry,))
    before, after = _mae(model, sample, dt), _mae(shaped, sample, dt)
    return (shaped if after < (1.0 - GEOMETRY_GAIN) * before else None), refit
