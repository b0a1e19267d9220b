"""
The SDP analysis of a joint: how its parameters depend on the candidate states.

The reasoning is in docs/methods.md sections 8.1, 14.6.

"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, Sequence

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.identification.delay import estimate_delay
from hydro_sdp.core.identification.experiment import split_long, thin
from hydro_sdp.core.identification.rest import estimate_rest_command
from hydro_sdp.core.identification.routine.detect import routine_operation
from hydro_sdp.core.identification.routine.increments import increment_delay
from hydro_sdp.core.identification.segmentation import check_records, segment_records
from hydro_sdp.core.identification.state_dependence.backfit import (
    Backfit, backfit, Term, with_tests)
from hydro_sdp.core.identification.state_dependence.dependence import (
    ordered, ParameterSummary, SdpAnalysis, StateDependence)
from hydro_sdp.core.identification.state_dependence.ordering import MAX_GROUPS
from hydro_sdp.core.identification.state_dependence.random_walk import order_of, TvpKind
from hydro_sdp.core.identification.state_dependence.states import (
    check_states, Rows, rows_of, STATES)
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Fewest samples a direction needs for its gain to be analysed.
MIN_SAMPLES = 20
#: Model increments below this share of the largest count as "the model does not move".
STILL = 1e-9
#: States whose gains remove alone within this share (relative) of the best one's are tied
#: for first: the one named first in the list is (full strokes make the travel since a
#: reversal the angle's twin, one each way).
TIED = 0.02


def rest_of(records: Sequence[Record]) -> float:
    """Return the valve's rest command: 0 when the commands take both signs, else from the data."""
    low = min(float(np.min(r.v)) for r in records)
    high = max(float(np.max(r.v)) for r in records)
    if low < 0.0 < high:
        return 0.0
    bottom = min(float(np.min(r.y)) for r in records)
    top = max(float(np.max(r.y)) for r in records)
    margin = max(1.0, 0.02 * (top - bottom))
    pieces = []
    for r in records:
        inside = np.r_[False, (r.y > bottom + margin) & (r.y < top - margin), False]
        edges = np.flatnonzero(np.diff(inside.astype(np.int8)))
        pieces += [(r.v[a:b], r.y[a:b]) for a, b in zip(edges[::2], edges[1::2])]
    return estimate_rest_command(pieces or [(r.v, r.y) for r in records])


def data_delay(records: Sequence[Record], dt: SamplePeriod, max_delay: float,
               rest: float) -> int:
    """Return the delay of model (2) found in the records, samples, as identify finds it."""
    longest = max(2, int(round(max_delay / dt)))
    segmentation = segment_records(records, max_delay=longest, rest=rest)
    pieces = thin(split_long(segmentation.experiments, 3000, longest), 100_000)
    if not routine_operation(records, rest, longest):
        try:
            found = estimate_delay(pieces, dt, max_delay=longest, rest=rest,
                                   noise=segmentation.noise_std)
            return found.samples + int(round(found.lag / dt))
        except HydroSdpError:
            pass
    # Commands that are seldom held have few change windows: the delay of routine operation.
    return increment_delay(pieces, dt, max_delay=longest, rest=rest).samples


def _split(values: FloatArray) -> list[tuple[str, FloatArray]]:
    """Return the positive and negative parts of a regressor that have enough samples."""
    parts = [('+', np.maximum(values, 0.0)), ('-', np.minimum(values, 0.0))]
    return [part for part in parts if np.count_nonzero(part[1]) >= MIN_SAMPLES]


@dataclass(frozen=True, eq=False)
class _Setting:
    """How every back-fit of one analysis is run, and the record of every row."""

    kind: TvpKind
    replicates: int
    max_groups: int | None
    seed: int
    segment: IntArray
    runs: IntArray | None = None
    screen: float = 0.0
    alone: dict[str, float] = field(default_factory=dict)

    def backfit(self, z: FloatArray, terms: list[Term], seed: int,
                start: Sequence[FloatArray | None] | None = None) -> Backfit:
        """Back-fit ``terms`` to ``z`` with this setting (from ``start``, if given)."""
        return backfit(z, terms, replicates=self.replicates, max_groups=self.max_groups,
                       seed=seed, segment=self.segment, start=start, runs=self.runs)

    def tested(self, fit: Backfit, z: FloatArray, names: Sequence[str], seed: int) -> Backfit:
        """Return ``fit`` (of ``z``, by :meth:`backfit` with ``seed``), ``names`` tested."""
        return with_tests(fit, z, names, replicates=self.replicates, seed=seed,
                          segment=self.segment, runs=self.runs)


class _Target:
    """One model of the analysis: its observations, its fixed terms and its gains."""

    def __init__(self, z: FloatArray, fixed: list[Term],
                 gains: list[tuple[str, FloatArray]]) -> None:
        self.z = z
        self.fixed = fixed
        self.gains = gains

    def alone(self, state: FloatArray, setting: _Setting, seed: int) -> Backfit:
        """Back-fit the gains along one state, untested (:meth:`_Setting.tested`)."""
        terms = self.fixed + [Term(name, x, state, setting.kind, test=False)
                              for name, x in self.gains]
        return setting.backfit(self.z, terms, seed)

    def given(self, first: FloatArray, state: FloatArray, setting: _Setting,
              seed: int, alone: Backfit) -> Backfit:
        """Back-fit the gains along ``first`` plus what they add along ``state``."""
        terms = self.fixed + [Term(name, x, first, setting.kind, test=False)
                              for name, x in self.gains]
        start: list[FloatArray | None] = [estimate.parameter for estimate in alone.terms]
        terms += [Term(f'{name} added', x, state, setting.kind, additive=True)
                  for name, x in self.gains]
        return setting.backfit(self.z, terms, seed, start + [None] * len(self.gains))


def _entries(fit: Backfit, state: str, parameter: str, names: list[str],
             given: str | None) -> list[StateDependence]:
    """Describe the gains of a back-fit (``given``: the terms added to that state's)."""
    out = []
    for name in names:
        term = fit.term(f'{name} added' if given else name)
        entry = StateDependence.of(state, parameter, _direction(name), term)
        if given:
            # Partial dependence: the first state's gain averaged out, this state's added.
            level = fit.term(name).constant
            entry = replace(entry, estimate=entry.estimate - term.constant + level,
                            constant=level, given=given)
        out.append(entry)
    return out


def _two_stages(target: _Target, rows: Rows, names: Sequence[str], parameter: str,
                setting: _Setting, progress: Callable[[str], None] | None,
                fits: dict[str, Backfit], prefix: str) -> list[StateDependence]:
    """Weigh the gains against every state: the best state alone, the others given it."""
    gain_names = [name for name, _ in target.gains]

    def step(name: str) -> None:
        if progress is not None:
            progress(f'{prefix}{name}')
    alone: dict[str, Backfit] = {}
    for name in names:
        step(name)
        alone[name] = target.alone(rows.state(name), setting, setting.seed)
        setting.alone[f'{prefix}{name}'] = sum(alone[name].term(g).share for g in gain_names)
    explained = {name: sum(alone[name].term(g).share for g in gain_names) for name in names}
    best = max(explained.values())
    first = next(name for name in names if explained[name] >= (1.0 - TIED) * best)
    step(first)
    # The first state's gains tested: the fit alone, weighed again (nothing refitted).
    fits[f'{prefix}{first}'] = setting.tested(alone[first], target.z, gain_names, setting.seed)
    entries = _entries(fits[f'{prefix}{first}'], first, parameter, gain_names, None)
    for index, name in enumerate(names):
        if name == first:
            continue
        step(name)
        if sum(alone[name].term(g).share for g in gain_names) < setting.screen:
            fits[f'{prefix}{name}'] = alone[name]
            entries += _entries(alone[name], name, parameter, gain_names, None)
            continue
        fit = target.given(rows.state(first), rows.state(name), setting,
                           setting.seed + 10 * (index + 1), alone[first])
        fits[f'{prefix}{name}'] = fit
        entries += _entries(fit, name, parameter, gain_names, first)
    return entries


def analyse(records: Sequence[Record], *, model: JointModel | None = None,
            states: Sequence[str] = STATES, delay: int | None = None, max_delay: float = 0.5,
            rest: float | None = None, kind: TvpKind = 'rw', replicates: int = 199,
            max_groups: int | None = MAX_GROUPS, seed: int = 0, max_rows: int | None = None,
            screen: float = 0.0,
            progress: Callable[[str], None] | None = None) -> SdpAnalysis:
    """
    Estimate how a joint's parameters depend on each candidate state.

    Parameters
    ----------
    records : sequence of Record
        Records of one joint, same sample period.
    model : JointModel or None
        None: the SDP-ARX model of the joint (``target = arx``); a model: what it
        misses (``target = ratio``).
    states : sequence of str
        Candidate states (:data:`~hydro_sdp.core.identification.state_dependence.states.STATES`);
        those the records cannot give (no other joints, no load) are skipped.
    delay : int or None
        Delay, samples; default: the model's, or estimated from the data.
    max_delay : float
        Largest delay considered when it is estimated, s.
    rest : float or None
        The valve's rest command; default: the model's, else 0 when the commands take
        both signs, else from the data (:func:`rest_of`).
    kind : str
        Walk of every parameter: ``rw`` (default; zero NVR: no dependence) or ``irw``.
    replicates : int
        Bootstrap replicates of each dependence test.
    max_groups : int or None
        Most groups per state.
    seed : int
        Seed of the bootstrap.
    max_rows : int or None
        Most rows analysed: beyond, every k-th row of the records (None: all).
    screen : float
        Share a state's gains must remove alone to be weighed given the first state
        and tested (0: every state is).
    progress : callable or None
        Called with the name of each back-fit as it starts (a state, ``residual
        <state>`` or ``a1``): ``2 n`` of them per target for ``n`` states, and ``a1``.

    Returns
    -------
    SdpAnalysis
        The parameters against the states: the first state's entries, then the others
        by what they add to it.

    See Also
    --------
    identify : the parametric model the analysis guides.

    Examples
    --------
    >>> from hydro_sdp import analyse
    >>> analysis = analyse(records, states=('command', 'angle'))  # doctest: +SKIP

    """
    names = check_states(list(states))
    order_of(kind)
    # A canonical order, so that the bags' order on the command line changes nothing.
    records = sorted(records, key=lambda r: (r.source, float(r.t[0]) if len(r) else 0.0,
                                             len(r), float(np.sum(r.v)), float(np.sum(r.y))))
    dt = check_records(records, 'analyse')
    if model is not None:
        tau = delay or model.delay_samples(dt)
        rest = model.rest_command if rest is None else rest
    else:
        rest = rest_of(records) if rest is None else rest
        tau = delay or data_delay(records, dt, max_delay, rest)
    rows, left_out = rows_of(records, tau, rest, model, dt, holds=True).free()
    if rows.samples < MIN_SAMPLES:
        raise DataError(f'only {rows.samples} increments where the joint can move (left out: '
                        + ', '.join(f'{count} {why}' for why, count in left_out.items()) + ')')
    if max_rows is not None and rows.samples > max_rows:
        rows = rows.every(-(-rows.samples // max_rows))
    usable, skipped = _usable(rows, names)
    setting = _Setting(kind, replicates, max_groups, seed, rows.record, rows.run, screen)
    fits: dict[str, Backfit] = {}
    residuals: list[StateDependence] = []
    a1_entries: list[StateDependence] = []
    a1 = None
    if model is None:
        gains = [(f'b{suffix}', x) for suffix, x in _split(rows.drive)]
        if not gains:
            raise DataError('the command never drives the joint (no samples away from rest)')
        # a1 is held constant while the gains are weighed, then smoothed along its own
        # regressor's state, the angle (Young's default), with the gains along the first
        # state: against the command, a1{v} y_{k-1} would mimic each step's speed over the
        # few degrees it travels. Angles from their mean: the model does not depend on
        # the sensor's zero, and no sum of large angles cancels.
        level = float(np.mean(rows.previous))
        y, previous, angle = rows.y - level, rows.previous - level, rows.state('angle')
        constant = Term('a1', -previous, angle, kind, nvr=0.0, test=False)
        entries = _two_stages(_Target(y, [constant], gains), rows, usable, 'b', setting,
                              progress, fits, '')
        if progress is not None:
            progress('a1')
        first = rows.state(entries[0].state)
        terms = [Term('a1', -previous, angle, kind)]
        terms += [Term(name, x, first, kind, test=False) for name, x in gains]
        fits['a1'] = setting.backfit(y, terms, seed + 1, [
            estimate.parameter for estimate in fits[entries[0].state].terms])
        a1_fit = fits['a1'].term('a1')
        a1 = ParameterSummary(a1_fit.constant, a1_fit.constant_se, a1_fit.nvr)
        a1_entries.append(StateDependence.of('angle', 'a1', 'both', a1_fit))
    else:
        assert rows.predicted is not None
        largest = float(np.max(np.abs(rows.predicted)))
        moving = np.where(np.abs(rows.predicted) > STILL * largest, rows.predicted, 0.0)
        gains = [(f'g{suffix}', x) for suffix, x in _split(moving)]
        if not gains:
            raise DataError('the model never moves the joint on these records')
        entries = _two_stages(_Target(rows.increment, [], gains), rows, usable, 'ratio',
                              setting, progress, fits, '')
        offset = _Target(rows.increment - rows.predicted, [], [('c', np.ones(rows.samples))])
        residuals = _two_stages(offset, rows, usable, 'residual', setting, progress, fits,
                                'residual ')
    return SdpAnalysis('arx' if model is None else 'ratio', rows.samples, tau, dt, rest,
                       ordered(entries), ordered(residuals), a1, tuple(a1_entries), fits,
                       tuple(skipped), dict(setting.alone), left_out)


def _usable(rows: Rows, names: Sequence[str]) -> tuple[list[str], list[tuple[str, str]]]:
    """Return the states the rows give and that vary, and the others with the reason."""
    usable, skipped = [], []
    for name in names:
        try:
            state = rows.state(name)
        except DataError as error:
            skipped.append((name, str(error).split(': ', 1)[-1]))
            continue
        if np.unique(state).size < 2:
            skipped.append((name, 'takes one value only'))
            continue
        usable.append(name)
    if not usable:
        reasons = '; '.join(f'{name}: {why}' for name, why in skipped)
        raise DataError(f'no state could be analysed ({reasons})')
    return usable, skipped


def _direction(name: str) -> str:
    if name.endswith('+'):
        return 'positive'
    return 'negative' if name.endswith('-') else 'both'
