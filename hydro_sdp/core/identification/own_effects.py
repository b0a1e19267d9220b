"""
The effects ``identify`` proposes by itself: checked on held-out experiments, then fitted.

A ``valve_lag`` comes with the dead time (:mod:`.change_windows`), a
``stroke_geometry`` factor when the runs span the stroke (:mod:`.stroke_fit`).
:func:`check_lag` and :func:`check_geometry` say whether each lowers the error
of experiments it was not fitted on by a clear margin (:mod:`.effect_check`);
:func:`shape_with_geometry` then refits the map under the factor.

"""

from __future__ import annotations

from dataclasses import replace
import math
from typing import Callable, Sequence

from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.identification.delay import DelayEstimate, level_speeds
from hydro_sdp.core.identification.effect_check import (
    compared, held_out, HeldOut, simulation_errors)
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.identification.family_choice import (
    fit_family, FittedKind, FoldFits, folds)
from hydro_sdp.core.identification.map_fit import fit_sdp, FitData, MapFit
from hydro_sdp.core.identification.stroke_fit import fit_stroke_geometry, speed_gains
from hydro_sdp.core.model.effects import StrokeGeometry
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import StaticMap

#: The stroke factor refitted with the map is kept when it lowers the simulation error of
#: the experiments by this share at least (after its held-out check).
GEOMETRY_GAIN = 0.05
#: Alternations of map and stroke factor.
GEOMETRY_ROUNDS = 3

#: Refits the chosen map family to data whose speeds carry known gains.
MapRefit = Callable[[FitData], MapFit[StaticMap]]


def check_lag(fold_fits: FoldFits, kind: FittedKind, delay: DelayEstimate,
              with_lag: Sequence[float] | None = None) -> HeldOut:
    """
    Held-out windowed error of the chosen family with the lag and with the best pure delay.

    On each fold the family is fitted on the training part with each timing (the dead
    time and lag, the best pure delay) and the windows of the test part are simulated
    with both (:mod:`.held_out`).

    Parameters
    ----------
    fold_fits : FoldFits
        The folds, fitted with the lag (:class:`~.family_choice.FoldFits`).
    kind : str
        The map family.
    delay : DelayEstimate
        The dead time with the lag, and the best pure delay.
    with_lag : sequence of float or None
        The family's error on each fold with the lag, if scored already.

    Returns
    -------
    HeldOut
        The judgement (:mod:`.effect_check`).

    """
    if with_lag is None:
        with_lag = _fold_errors(fold_fits, kind, delay.samples, delay.lag)
    pure = delay.without_lag(fold_fits.dt)
    without = _fold_errors(fold_fits, kind, pure.samples, 0.0)
    if delay.lag <= 0.0:
        return compared('valve_lag', [], [])
    weights = [float(fold.held_out.samples) for fold in fold_fits.folds]
    return compared('valve_lag', list(zip(without, with_lag)), weights)


def _fold_errors(fold_fits: FoldFits, kind: FittedKind, samples: int, lag: float
                 ) -> list[float]:
    """Each fold's held-out error of ``kind`` fitted on its training part with this timing."""
    errors = []
    dt, rest = fold_fits.dt, fold_fits.rest
    for fold in fold_fits.folds:
        train, test = fold.data.experiments, fold.held_out.experiments
        data = FitData(train, samples, dt, lag)
        points = level_speeds(train, samples, dt, rest=rest)
        try:
            start = fit_sdp(data, points, rest, starts=2).static_map
            static_map = start if kind == 'sdp' else fit_family(
                kind, data, points, rest, fold_fits.method, start, starts=2).static_map
            errors.append(FitData(test, samples, dt, lag).simulation_mae(static_map.rate))
        except HydroSdpError:
            errors.append(math.nan)
    return errors


def check_geometry(experiments: Sequence[Experiment], model: JointModel, delay: DelayEstimate,
                   dt: float, stops: tuple[float | None, float | None],
                   reach: float) -> HeldOut:
    """
    Held-out errors of the model without and with a stroke factor fitted on each training part.

    Parameters
    ----------
    experiments : sequence of Experiment
        Experiments to deal into folds (:func:`~.family_choice.folds`).
    model : JointModel
        The model without the factor (its map fitted on all experiments).
    delay : DelayEstimate
        Delay and lag.
    dt : float
        Sample period, s.
    stops : tuple
        End stops seen, degrees.
    reach : float
        How near a stop counts as at it, degrees.

    Returns
    -------
    HeldOut
        The comparison (:mod:`.effect_check`).

    """
    def shaped(train: Sequence[Experiment]) -> JointModel | None:
        geometry = fit_stroke_geometry(train, model.static_map.rate, delay.samples, dt,
                                       delay.lag, stops, reach, delay.transient)
        return None if geometry is None else replace(model, effects=model.effects + (geometry,))
    return held_out('stroke_geometry', folds(experiments, model.rest_command),
                    lambda train: model, shaped, dt)


def _mae(model: JointModel, experiments: Sequence[Experiment], dt: float) -> float:
    total, count = simulation_errors(model, experiments, dt)
    return total / max(count, 1)


def shape_with_geometry(model: JointModel, geometry: StrokeGeometry | None, refit_map: MapRefit,
                        first: MapFit[StaticMap], pieces: Sequence[Experiment],
                        sample: Sequence[Experiment], delay: DelayEstimate, dt: float,
                        stops: tuple[float | None, float | None], reach: float
                        ) -> tuple[JointModel | None, MapFit[StaticMap]]:
    """
    Refit the map under the stroke factor, then the factor under the new map, in turn.

    The two share the speed's scale, so they alternate (:data:`GEOMETRY_ROUNDS`);
    the result stands when it lowers the error of the experiments by
    :data:`GEOMETRY_GAIN`.

    Parameters
    ----------
    model : JointModel
        The model without the factor.
    geometry : StrokeGeometry or None
        The factor fitted under the model's map.
    refit_map : callable
        Refits the chosen map family to data with known gains on the speed.
    first : MapFit
        The fit of the chosen map family without the factor.
    pieces, sample : sequence of Experiment
        All experiments, and the (thinned) ones the factor is fitted on.
    delay : DelayEstimate
        Delay and lag.
    dt : float
        Sample period, s.
    stops : tuple
        End stops seen, degrees.
    reach : float
        How near a stop counts as at it, degrees.

    Returns
    -------
    tuple
        ``(model, fit)``: the shaped model (None when it gains too little) and the
        map fit under the factor.

    """
    refit = first
    for _ in range(GEOMETRY_ROUNDS):
        if geometry is None:
            break
        # The factor is taken at the measured angles: known gains on the speed.
        refit = refit_map(FitData(pieces, delay.samples, dt, delay.lag, speed_gains(
            pieces, refit.static_map.rate, delay.samples, dt, delay.lag, geometry)))
        geometry = fit_stroke_geometry(sample, refit.static_map.rate, delay.samples, dt,
                                       delay.lag, stops, reach, delay.transient)
    if geometry is None:
        return None, refit
    shaped = replace(model, static_map=refit.static_map, effects=model.effects + (geometry,))
    before, after = _mae(model, sample, dt), _mae(shaped, sample, dt)
    return (shaped if after < (1.0 - GEOMETRY_GAIN) * before else None), refit
