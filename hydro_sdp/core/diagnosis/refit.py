"""Static maps refitted with chosen features: dead-zone, saturation, asymmetry (methods 8.2)."""

from __future__ import annotations

from dataclasses import replace
import math
from typing import NamedTuple

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.residuals import velocity_residuals
from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.identification.delay import level_speeds, LevelSpeed
from hydro_sdp.core.identification.map_fit import fit_sdp, FitData
from hydro_sdp.core.identification.map_fit.power_sat import fit_power_sat
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import (
    LinearMap, PowerSatMap, SdpDzMap, SdpMap, StaticMap)
import numpy as np
from scipy.optimize import least_squares


#: Exponents of a ``power_sat`` side (the bounds identify fits them in).
EXPONENTS = (0.5, 8.0)
#: Maps a refit builds.
RefitMap = SdpMap | SdpDzMap | PowerSatMap


class Features(NamedTuple):
    """Which features a static map has, and whether its sides start as a power."""

    dead_zone: bool
    saturation: bool
    asymmetric: bool
    power: bool = False


def map_features(static_map: StaticMap) -> Features:
    """Return whether a map has a dead-zone, saturates and treats the directions apart."""
    if isinstance(static_map, LinearMap):
        return Features(False, False, False)
    if isinstance(static_map, SdpDzMap):
        low, high = static_map.dead_zone
        same = math.isclose(static_map.slope[0], static_map.slope[1], rel_tol=1e-6)
        return Features(high > low, False, not same)
    if isinstance(static_map, SdpMap):
        low, high = static_map.dead_zone
        vn, vp = static_map.saturation_velocity
        cn, cp = static_map.curvature
        symmetric = math.isclose(-vn, vp, rel_tol=1e-6) and math.isclose(cn, cp, rel_tol=1e-6)
        return Features(high > low, True, not symmetric)
    if isinstance(static_map, PowerSatMap):
        low, high = static_map.dead_zone
        vn, vp = static_map.saturation_velocity
        symmetric = math.isclose(-vn, vp, rel_tol=1e-6) and all(
            math.isclose(n, p, rel_tol=1e-6)
            for n, p in (static_map.curvature, static_map.exponent))
        return Features(high > low, True, not symmetric, True)
    return Features(True, True, True)


class MapFamily:
    """
    Static maps with a chosen set of features, as functions of free parameters.

    ``rest``: rest command, input units.
    ``scale``: largest distance of a command from ``rest``, input units.
    """

    def __init__(self, features: Features, rest: float, scale: float) -> None:
        self.dead_zone, self.saturation, self.asymmetric, power = features
        self.power = power and self.saturation
        self.rest, self.scale = rest, scale

    def build(self, x: FloatArray) -> RefitMap:
        """Return the map for free parameters ``x``."""
        i = 0
        if self.dead_zone:
            # Edges stay inside the commands seen (a runaway edge explains nothing).
            low = self.rest - min(math.exp(min(x[0], 50.0)), self.scale)
            high = self.rest + min(math.exp(min(x[1], 50.0)), self.scale)
            i = 2
        else:
            low = high = self.rest
        x = np.clip(x, -50.0, 50.0)
        (a, b), i = self._sides(x, i)
        a, b = math.exp(a), math.exp(b)
        if not self.saturation:
            return SdpDzMap(dead_zone=(low, high), slope=(a, b))
        (cn, cp), i = self._sides(x, i)
        cn, cp = math.exp(cn), math.exp(cp)
        if not self.power:
            return SdpMap(dead_zone=(low, high), saturation_velocity=(-a, b),
                          curvature=(cn, cp))
        # The exponent rides on a logistic between identify's bounds.
        nn, np_ = (EXPONENTS[0] + (EXPONENTS[1] - EXPONENTS[0]) / (1.0 + math.exp(-value))
                   for value in self._sides(x, i)[0])
        return PowerSatMap(dead_zone=(low, high), saturation_velocity=(-a, b),
                           curvature=(cn, cp), exponent=(nn, np_))

    def _sides(self, x: FloatArray, i: int) -> tuple[tuple[float, float], int]:
        """Return the negative and positive side's parameter at ``x[i]``, and the next index."""
        if self.asymmetric:
            return (float(x[i]), float(x[i + 1])), i + 2
        return (float(x[i]), float(x[i])), i + 1

    def start(self, static_map: StaticMap) -> FloatArray:
        """Free parameters near ``static_map`` (any kind), for a fit to start from."""
        v = np.linspace(self.rest - self.scale, self.rest + self.scale, 41)
        speeds = static_map.rate(v)
        edge = 0.05 * self.scale
        x: list[float] = []
        if self.dead_zone:
            zone = getattr(static_map, 'dead_zone', None)
            low, high = zone if zone and zone[1] > zone[0] else \
                (self.rest - edge, self.rest + edge)
            x += [math.log(max(self.rest - low, 1e-3 * self.scale)),
                  math.log(max(high - self.rest, 1e-3 * self.scale))]
        top = max(abs(speeds[0]), 1e-6), max(abs(speeds[-1]), 1e-6)
        curvature: list[float] | None
        if self.saturation:
            sizes = [1.2 * top[0], 1.2 * top[1]]
            curvature = [2.0 / self.scale] * 2
            if isinstance(static_map, (SdpMap, PowerSatMap)):
                sizes = [-static_map.saturation_velocity[0], static_map.saturation_velocity[1]]
                curvature = list(static_map.curvature)
        else:
            sizes = [top[0] / self.scale, top[1] / self.scale]
            curvature = None
            if isinstance(static_map, SdpDzMap):
                sizes = list(static_map.slope)
        x += [math.log(sizes[0]), math.log(sizes[1])] if self.asymmetric else \
            [math.log(0.5 * (sizes[0] + sizes[1]))]
        if curvature is not None:
            x += [math.log(curvature[0]), math.log(curvature[1])] if self.asymmetric else \
                [math.log(0.5 * (curvature[0] + curvature[1]))]
        if self.power:
            # From the map's own exponents, or from eq. (5) (exponent 1).
            exponents = static_map.exponent if isinstance(static_map, PowerSatMap) else (1.0, 1.0)
            shares = [min(max((n - EXPONENTS[0]) / (EXPONENTS[1] - EXPONENTS[0]), 1e-6),
                          1.0 - 1e-6) for n in exponents]
            logits = [math.log(share / (1.0 - share)) for share in shares]
            x += logits if self.asymmetric else [0.5 * (logits[0] + logits[1])]
        return np.array(x)


def _fit_family(model: JointModel, family: MapFamily, data: FitData) -> RefitMap:
    x0 = family.start(model.static_map)

    def residuals(p: FloatArray) -> FloatArray:
        return data.residuals(family.build(p[:-1]).rate, 1.0 / (1.0 + math.exp(-p[-1])))
    result = least_squares(residuals, np.r_[x0, 0.0], method='lm')
    return family.build(result.x[:-1])


def _polish(context: Context, model: JointModel, family: MapFamily) -> JointModel:
    """Fit the family's parameters on the one-step velocity residuals the score uses."""
    def residuals(x: FloatArray) -> FloatArray:
        candidate = replace(model, static_map=family.build(x))
        return np.concatenate(velocity_residuals(candidate, context.runs))
    x0 = family.start(model.static_map)
    result = least_squares(residuals, x0, method='trf', x_scale='jac', max_nfev=40 * x0.size)
    return replace(model, static_map=family.build(result.x))


class _Fits(NamedTuple):
    """What every family's refit starts from: the experiments and, for a full map, eq. (5)."""

    data: FitData
    #: The data's level speeds and identify's eq. (5) fit (a full map's refit only).
    full: tuple[list[LevelSpeed], SdpMap] | None


def _fits(context: Context, samples: int, full: bool) -> _Fits | None:
    """Return the experiments at ``samples`` and, when ``full``, identify's eq. (5) fit."""
    try:
        data = context.fit_data(samples)
    except (HydroSdpError, np.linalg.LinAlgError, ValueError):
        return None  # No experiments: every family starts from the model's own map.
    if not full:
        return _Fits(data, None)
    try:
        # The full map: identify's fits, started from the data's speeds.
        points = level_speeds(data.experiments, samples, context.dt, rest=context.rest)
        return _Fits(data, (points, fit_sdp(data, points, context.rest).static_map))
    except (HydroSdpError, np.linalg.LinAlgError, ValueError):
        return _Fits(data, None)


def _refit_in(context: Context, model: JointModel, features: Features,
              fits: _Fits | None) -> JointModel:
    """Refit the map of ``model`` in the family of ``features`` and polish it."""
    family = MapFamily(features, rest=context.rest, scale=context.scale)
    starts = [replace(model, static_map=family.build(family.start(model.static_map)))]
    if fits is not None:
        try:
            if not all(features[:3]):
                starts.append(replace(model, static_map=_fit_family(model, family, fits.data)))
            elif fits.full is not None:
                points, sdp = fits.full
                starts.append(replace(model, static_map=sdp))
                if family.power:
                    starts.append(replace(model, static_map=fit_power_sat(
                        fits.data, points, context.rest, sdp).static_map))
        except (HydroSdpError, np.linalg.LinAlgError, ValueError):
            pass  # The experiments do not support a fit: start from the model's own map.
    best = min(starts, key=context.squared_residual)
    return _polish(context, best, family)


def refit_map(context: Context, features: Features, delay: float | None = None) -> JointModel:
    """
    Return the model under test with its map refitted to have ``features``.

    ``delay``: delay to fit at, s (default: the model's).
    """
    model = context.model if delay is None else replace(context.model, delay=delay)
    families = [features]
    # A convex start from rest is what a dead-zone does: power_sat is tried only beyond
    # edges the map already has (the dead_zone word tests a zone on its own).
    if features.saturation and features.dead_zone and not features.power and \
            not map_features(model.static_map).saturation:
        families.append(features._replace(power=True))
    # The experiments and eq. (5) are fitted once for every family tried.
    fits = _fits(context, model.delay_samples(context.dt), all(features[:3]))
    refits = [_refit_in(context, model, family, fits) for family in families]
    return min(refits, key=context.squared_residual)


def map_parameters(model: JointModel) -> dict[str, object]:
    """Return the model's map as the parameters of a candidate."""
    return dict(model.static_map.to_mapping())
