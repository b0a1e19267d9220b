"""Detectors of valve lag, backlash and the link's mode (methods 8.2)."""

from __future__ import annotations

from dataclasses import replace
from functools import cache
import math
from typing import Callable, Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import EffectDetector
from hydro_sdp.core.diagnosis.residuals import block_sums
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.model.effects import (
    Backlash, DirectionDependentDelay, Oscillation, ValveLag)
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.sample_period import whole_samples_seconds
from hydro_sdp.core.model.simulation import OneStep
from hydro_sdp.core.model.timing import delay_samples, SamplePeriod
import numpy as np
from scipy.ndimage import median_filter
from scipy.optimize import minimize


class ValveLagDetector(EffectDetector):
    """The speed approaches each new level with a first-order lag: fit its time constant."""

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
_GRID_FREQUENCIES = 12
_GRID_DAMPING = (0.05, 0.15, 0.3, 0.5)
#: Width of the spectrum's running median a mode's line is measured against, Hz.
_BACKGROUND = 2.0
#: Grid points polished, at frequencies apart.
_POLISHED = 2
#: Largest damping ratio of a mode named: a better damped one overshoots by less than
#: 31 % and stands in for a lag or a delay (on settled plant runs, 0.6 Hz at 0.48).
RINGING = 0.35
#: How much shorter than the model's the dead time is searched with the mode, s.
SHORTER = 0.3
#: Turns of the search of the dead time and the mode, one after the other.
_TURNS = 3
#: A line of the residual's spectrum this many times over its running median, at
#: :data:`LINE_LOWEST` Hz or more, is reported with the mode's candidate, fitted or not
#: (methods 8.2: on 216 grid cases with no ring, at most 2.7 times from 1 Hz).
LINE = 4.0
#: Lowest frequency a line is reported at, Hz: below, a model's slow misses stand as high.
LINE_LOWEST = 1.0

Fit = tuple[float, float, float]


class OscillationDetector(EffectDetector):
    """The link rings on the oil column after starts, stops and reversals: fit its mode."""

    word = 'oscillation'
    description = 'the joint rings after starts, stops and reversals'
    remedy = 'effect, frequency and damping fitted (and the delay with them)'
    feature = 'events'
    state = 'since_change'

    def fit_effect(self, context: Context) -> Trial:
        """Fit the mode's frequency and damping, and the delay with them; score it."""
        low, high = MODE_FREQUENCIES[0], min(MODE_FREQUENCIES[1], 0.4 / context.dt)
        if not high > low:
            return Candidate(self.word, False, evidence='the sample period is too long to '
                             'show a mode'), None
        model, dt = context.model, context.dt
        # The residual's spectrum seeds the fit and shows a line the fit may not follow.
        spectrum = _spectrum(context.base, dt)
        split = model.effect(DirectionDependentDelay.name)
        delays = {'delay': model.delay}
        if isinstance(split, DirectionDependentDelay):
            delays = {'positive': split.positive, 'negative': split.negative}
        period = SamplePeriod(dt)
        samples = {key: delay_samples(value, period) for key, value in delays.items()}

        def shortened(by: int) -> JointModel:
            """Return the model with every dead time it has ``by`` samples shorter."""
            if not by:
                return model
            if isinstance(split, DirectionDependentDelay):
                # The split dead times replace the model's own; kept in their place.
                split_now = DirectionDependentDelay(
                    whole_samples_seconds(samples['positive'] - by, dt),
                    whole_samples_seconds(samples['negative'] - by, dt))
                return replace(model, effects=tuple(
                    split_now if effect is split else effect for effect in model.effects))
            return replace(model, delay=whole_samples_seconds(samples['delay'] - by, dt))

        def with_mode(by: int, x: FloatArray) -> JointModel:
            frequency = min(max(math.exp(float(x[0])), low), high)
            damping = min(max(float(x[1]), MODE_DAMPING[0]), MODE_DAMPING[1])
            return shortened(by).with_effect(Oscillation(frequency, damping))

        # Built once per dead time: the scan of the dead times and the polish there share it.
        @cache
        def cost_at(by: int) -> Callable[[FloatArray], float]:
            # The model's increments without the mode are the same for every mode tried.
            timed = shortened(by).without_effect(Oscillation.name)
            steps = [(OneStep(timed, run.record.v, run.record.y, dt, start=run.start,
                              v_before=float(run.record.v[0]), exogenous=run.exogenous),
                      np.diff(run.record.y[run.start:]), run.free) for run in context.runs]

            def cost(x: FloatArray) -> float:
                mode = with_mode(by, x).effect(Oscillation.name)
                assert isinstance(mode, Oscillation)
                residuals = [measured - step.increments(mode) if free is None else
                             np.where(free, measured - step.increments(mode), 0.0)
                             for step, measured, free in steps]
                return float(block_sums(residuals, context.block).sum())
            return cost

        def fit_at(by: int, start: FloatArray | None = None) -> tuple[float, FloatArray]:
            cost = cost_at(by)
            seeds = [start] if start is not None else _seeds(spectrum, dt, cost, low, high)
            best: tuple[float, FloatArray] = (math.inf, np.zeros(2))
            for x0 in seeds:
                result = minimize(cost, x0, method='Nelder-Mead', options={
                    'xatol': 1e-3, 'fatol': 1e-6 * cost(x0), 'maxiter': 40 if start is not None
                    else 120, 'initial_simplex': np.array([x0, x0 + [0.1, 0.0],
                                                           x0 * [1.0, 1.3]])})
                if result.fun < best[0]:
                    best = (float(result.fun), np.asarray(result.x, dtype=np.float64))
            return best

        fits = {0: fit_at(0)}
        # The dead times that are the model's own (the split ones when it has them) are
        # shortened together: the mode's lag is the same in both directions.
        longest = max(0, min(int(round(SHORTER / dt)), min(samples.values()) - 1))
        by = 0
        # The dead time and the mode trade against each other (the mode lags the actuator):
        # in turns, the dead time that fits best at the mode found, then the mode polished
        # at that dead time, until the dead time stays.
        for _ in range(_TURNS if longest else 0):
            mode_found = fits[by][1]
            # Of equal fits, the shortest dead time.
            best = min(range(longest, -1, -1),
                       key=lambda tried: cost_at(tried)(mode_found))
            if best in fits:
                break
            fits[best] = fit_at(best, mode_found)
            by = best
        by = min(fits, key=lambda k: fits[k][0])
        augmented = with_mode(by, fits[by][1])
        mode = augmented.effect(Oscillation.name)
        assert isinstance(mode, Oscillation)
        line = _line(spectrum, high)
        if mode.damping > RINGING:
            # Looked for and not found: a finding of the runs, shown with the others.
            return Candidate(self.word, True, evidence=(
                f'the best mode ({mode.frequency:.3g} Hz) is damped at {mode.damping:.2g}, '
                f'above {RINGING:g}: it does not ring but stands in for a lag or a delay'
                + ('' if line is None else f'; yet {line}: the joint may ring there in a '
                   'way a mode from rest does not follow'))), None
        parameters: dict[str, object] = {'frequency': mode.frequency, 'damping': mode.damping}
        evidence = (f'after each change of speed the angle rings at {mode.frequency:.3g} Hz '
                    f'with a damping ratio of {mode.damping:.2g}')
        if by:
            now = augmented.effect(DirectionDependentDelay.name)
            if isinstance(now, DirectionDependentDelay) and isinstance(
                    split, DirectionDependentDelay):
                parameters.update(positive=now.positive, negative=now.negative)
                evidence += (f', the dead times {now.positive:g} and {now.negative:g} s, not '
                             f'{split.positive:g} and {split.negative:g} s')
            else:
                parameters['delay'] = augmented.delay
                evidence += f', the dead time {augmented.delay:g} s, not {model.delay:g} s'
            evidence += " (the link's lag was taken for delay)"
        if line is not None:
            evidence += f'; {line}'
        return context.score(self.word, augmented, parameters, evidence)


def _seeds(spectrum: Spectrum | None, dt: float, cost: Callable[[FloatArray], float],
           low: float, high: float) -> list[FloatArray]:
    """Return the starts of the polish: the best grid points at frequencies apart."""
    starts = [(f, d) for f in np.geomspace(low, high, _GRID_FREQUENCIES) for d in _GRID_DAMPING]
    starts += [(peak, d) for peak in _spectral_peaks(spectrum, dt, low, high)
               for d in _GRID_DAMPING]
    costs = [cost(np.array([math.log(f), d])) for f, d in starts]
    seeds: list[tuple[float, float]] = []
    for index in np.argsort(costs):
        f, d = starts[int(index)]
        if all(abs(math.log(f / other)) > 0.2 for other, _ in seeds):
            seeds.append((f, d))
        if len(seeds) == _POLISHED:
            break
    return [np.array([math.log(f), d]) for f, d in seeds]


#: An averaged periodogram: frequencies (Hz), power and its running median.
Spectrum = tuple[FloatArray, FloatArray, FloatArray]


def _spectrum(residuals: Sequence[FloatArray], dt: float) -> Spectrum | None:
    """
    Return the residuals' averaged periodogram: frequencies, power and its running median.

    Over 8 s Hann windows, half overlapping; None when no run is that long.
    """
    power: FloatArray | None = None
    size = max(64, int(round(8.0 / dt)))
    for residual in residuals:
        for first in range(0, residual.size - size + 1, size // 2):
            piece = residual[first:first + size]
            periodogram = np.abs(np.fft.rfft((piece - piece.mean()) * np.hanning(size))) ** 2
            power = periodogram if power is None else power + periodogram
    if power is None:
        return None
    # A model's slow misses raise the low frequencies, over which a lightly damped mode
    # stands out only as a line above its neighbours.
    width = 2 * int(round(0.5 * _BACKGROUND * size * dt)) + 1
    background = np.maximum(median_filter(power, size=width, mode='nearest'), 1e-300)
    return np.fft.rfftfreq(size, dt), power, background


def _spectral_peaks(spectrum: Spectrum | None, dt: float, low: float,
                    high: float) -> list[float]:
    """Return where the residual's spectrum stands highest over white noise's, and over its own."""
    if spectrum is None:
        return []
    frequencies, power, background = spectrum
    band = np.flatnonzero((frequencies >= low) & (frequencies <= high))
    if not band.size:
        return []
    white = np.abs(1.0 - np.exp(-2j * np.pi * frequencies * dt)) ** 2
    peaks = [float(frequencies[band[int(np.argmax(power[band] / floor[band]))]])
             for floor in (white, background)]
    return list(dict.fromkeys(peaks))


def spectral_line(residuals: Sequence[FloatArray], dt: float, high: float) -> tuple[float, float]:
    """
    Return the residuals' strongest line over its neighbours: frequency (Hz) and how many times.

    Looked for from :data:`LINE_LOWEST` to ``high`` Hz; ``(nan, nan)`` when the runs are
    shorter than the periodogram's 8 s windows or the band is empty.
    """
    return _strongest_line(_spectrum(residuals, dt), high)


def _strongest_line(spectrum: Spectrum | None, high: float) -> tuple[float, float]:
    """Return :func:`spectral_line`'s answer from the spectrum."""
    if spectrum is None:
        return math.nan, math.nan
    frequencies, power, background = spectrum
    band = np.flatnonzero((frequencies >= LINE_LOWEST) & (frequencies <= high))
    if not band.size:
        return math.nan, math.nan
    ratio = power[band] / background[band]
    strongest = int(np.argmax(ratio))
    return float(frequencies[band[strongest]]), float(ratio[strongest])


def _line(spectrum: Spectrum | None, high: float) -> str | None:
    """Return the residual's line in words when it stands :data:`LINE` times over its own."""
    frequency, times = _strongest_line(spectrum, high)
    if not times >= LINE:
        return None
    return (f"the residual's spectrum stands {times:.2g} times over its neighbours at "
            f'{frequency:.3g} Hz')
