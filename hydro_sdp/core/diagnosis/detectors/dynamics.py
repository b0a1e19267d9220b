"""Detectors of the valve's and the linkage's dynamics: valve lag, backlash, the link's mode."""

from __future__ import annotations

import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import EffectDetector
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.model.effects import Backlash, Oscillation, ValveLag
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np
from scipy.optimize import minimize


class ValveLagDetector(EffectDetector):
    """
    The speed approaches each new level with a first-order lag: fit its time constant.

    A model with a lag has it fitted again: a time constant that is far off (a short
    lag traded for a longer delay) is named and corrected like a missing one.

    """

    word = 'valve_lag'
    description = 'the speed approaches each new level with a lag'
    remedy = 'effect, time constant fitted'
    feature = 'events'
    state = 'since_change'
    refits = True

    def fit_effect(self, context: Context) -> Trial:
        """Fit the time constant between a fifth of a sample and 2 s, and score it."""
        finding = 'after each command change the speed settles with a time constant of {} s'
        present = context.model.effect(self.word)
        if isinstance(present, ValveLag):
            finding += f', not {present.time_constant:.3g} s'
        return self.fit_one_parameter(context, ValveLag, 'time_constant', (0.2 * context.dt, 2.0),
                                      finding, log=True)


class BacklashDetector(EffectDetector):
    """After a reversal the joint loses motion: fit the play."""

    word = 'backlash'
    description = 'after a reversal the joint loses motion'
    remedy = 'effect, play fitted'
    feature = 'reversals'
    state = 'reversals'

    def fit_effect(self, context: Context) -> Trial:
        """Fit the play between 0 and 10 degrees, and score it."""
        return self.fit_one_parameter(
            context, Backlash, 'play', (0.0, 10.0),
            'after each reversal the angle stands still while {} deg of play are taken up')


#: Frequencies the link's mode is looked for at, Hz (up to 0.4 of the sampling rate).
MODE_FREQUENCIES = (0.2, 15.0)
#: Damping ratios it is looked for at: a ringing mode; a better damped one is a lag's.
MODE_DAMPING = (0.02, 0.6)
#: The coarse grid the fit starts from: frequencies and damping ratios.
_GRID_FREQUENCIES = 14
_GRID_DAMPING = (0.05, 0.15, 0.3, 0.5)
#: Grid points polished, at frequencies apart.
_POLISHED = 3


class OscillationDetector(EffectDetector):
    """
    The link rings on the oil column after starts, stops and reversals: fit its mode.

    Frequency and damping minimise the blocked squared velocity residual, polished
    from the best points of a coarse grid and of the residual's spectral peak at
    frequencies apart (docs/methods.md section 8.2).

    """

    word = 'oscillation'
    description = 'the joint rings after starts, stops and reversals'
    remedy = 'effect, frequency and damping fitted'
    feature = 'events'
    state = 'since_change'

    def fit_effect(self, context: Context) -> Trial:
        """Fit the mode's frequency and damping, and score it."""
        low, high = MODE_FREQUENCIES[0], min(MODE_FREQUENCIES[1], 0.4 / context.dt)
        if not high > low:
            return Candidate(self.word, False, evidence='the sample period is too long to '
                             'show a mode'), None

        def model_with(frequency: float, damping: float) -> JointModel:
            return context.model.with_effect(Oscillation(frequency, damping))

        def cost(x: FloatArray) -> float:
            frequency = min(max(math.exp(float(x[0])), low), high)
            damping = min(max(float(x[1]), MODE_DAMPING[0]), MODE_DAMPING[1])
            return context.squared_residual(model_with(frequency, damping))

        starts = [(f, d) for f in np.geomspace(low, high, _GRID_FREQUENCIES)
                  for d in _GRID_DAMPING]
        peak = _spectral_peak(context, low, high)
        if peak is not None:
            starts += [(peak, d) for d in _GRID_DAMPING]
        costs = [cost(np.array([math.log(f), d])) for f, d in starts]
        # Polished from the best grid point of each of the best frequencies: a mode and a
        # harmonic of it (or a better damped one elsewhere) can come close on the grid.
        order = np.argsort(costs)
        seeds: list[tuple[float, float]] = []
        for index in order:
            f, d = starts[int(index)]
            if all(abs(math.log(f / other)) > 0.2 for other, _ in seeds):
                seeds.append((f, d))
            if len(seeds) == _POLISHED:
                break
        best_x, best_cost = np.zeros(2), math.inf
        for f, d in seeds:
            x0 = np.array([math.log(f), d])
            result = minimize(cost, x0, method='Nelder-Mead',
                              options={'xatol': 1e-3, 'fatol': 1e-9 * min(costs),
                                       'maxiter': 150, 'initial_simplex': np.array(
                                           [x0, x0 + [0.1, 0.0], x0 * [1.0, 1.3]])})
            if result.fun < best_cost:
                best_x, best_cost = result.x, float(result.fun)
        frequency = min(max(math.exp(float(best_x[0])), low), high)
        damping = min(max(float(best_x[1]), MODE_DAMPING[0]), MODE_DAMPING[1])
        return context.score(
            self.word, model_with(frequency, damping),
            {'frequency': frequency, 'damping': damping},
            f'after each change of speed the angle rings at {frequency:.3g} Hz with a '
            f'damping ratio of {damping:.2g}')


def _spectral_peak(context: Context, low: float, high: float) -> float | None:
    """
    Return the frequency where the residual's spectrum stands highest over white noise's.

    The velocity residual's periodogram over the runs, divided by what white angle noise
    gives a difference (``|1 - e^-iwdt|^2``), between ``low`` and ``high`` Hz.
    """
    power: FloatArray | None = None
    size = max(64, int(round(8.0 / context.dt)))
    for residual in context.base:
        for first in range(0, residual.size - size + 1, size // 2):
            piece = residual[first:first + size]
            spectrum = np.abs(np.fft.rfft((piece - piece.mean()) * np.hanning(size))) ** 2
            power = spectrum if power is None else power + spectrum
    if power is None:
        return None
    frequencies = np.fft.rfftfreq(size, context.dt)
    band = (frequencies >= low) & (frequencies <= high)
    if not band.any():
        return None
    white = np.abs(1.0 - np.exp(-2j * np.pi * frequencies * context.dt)) ** 2
    index = np.flatnonzero(band)[int(np.argmax(power[band] / white[band]))]
    return float(frequencies[index])
