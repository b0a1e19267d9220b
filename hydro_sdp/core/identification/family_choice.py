"""
Choosing the map family on held-out experiments, with folds that never extrapolate.

A held-out score is fair only when every fold's training part spans the
commands its test part holds: both directions, and the levels on either side.
Step experiments are stratified by direction and level: a level held several
times is dealt out over the folds; a level held once (full-stroke runs at one
duty each) is left out in turn only when it lies strictly inside its
direction's range, so the fit interpolates it (leave-one-level-out), and the
outermost levels always train. Runs of changing commands, whose levels
spread over the range anyway, alternate between the folds in pairs.

"""

from __future__ import annotations

from collections import defaultdict
import math
from typing import Sequence

from hydro_sdp.core.identification.segmentation import Experiment
import numpy as np

#: Most folds of the leave-one-level-out scheme.
MAX_FOLDS = 4


def _key(experiment: Experiment) -> tuple[str, float, int, float]:
    return (experiment.source, experiment.t0, experiment.y.size, float(np.sum(experiment.y)))


def folds(experiments: Sequence[Experiment], rest: float
          ) -> list[tuple[list[Experiment], list[Experiment]]]:
    """
    Training and test parts of each fold.

    Parameters
    ----------
    experiments : sequence of Experiment
        All experiments.
    rest : float
        Rest command (splits the directions).

    Returns
    -------
    list of (train, test)
        Two or more folds; every test part non-empty, no test level outside the
        range of its training part's levels on the same side of rest.

    """
    ordered = sorted(experiments, key=_key)
    steps = [e for e in ordered if e.kind == 'step' and math.isfinite(e.level)]
    runs = [e for e in ordered if not (e.kind == 'step' and math.isfinite(e.level))]
    strata: dict[float, list[Experiment]] = defaultdict(list)
    for experiment in steps:
        strata[experiment.level].append(experiment)
    repeated = {level: members for level, members in strata.items() if len(members) >= 2}
    single = sorted(level for level, members in strata.items() if len(members) == 1)
    interior: list[list[float]] = []
    for sign in (-1.0, 1.0):
        side = sorted((level for level in strata if sign * (level - rest) > 0),
                      key=lambda level: abs(level - rest))
        inner = set(side[1:-1])
        interior.append([level for level in single if level in inner])
    count = max(2, min(MAX_FOLDS, max(len(levels) for levels in interior)))
    assignment: dict[int, int] = {}
    for members in repeated.values():
        for index, experiment in enumerate(members):
            assignment[id(experiment)] = index % count
    for levels in interior:
        for index, level in enumerate(levels):
            assignment[id(strata[level][0])] = index % count
    for index, experiment in enumerate(runs):
        assignment[id(experiment)] = index // 2 % count
    out = []
    for fold in range(count):
        test = [e for e in ordered if assignment.get(id(e)) == fold]
        train = [e for e in ordered if assignment.get(id(e)) != fold]
        if test and train:
            out.append((train, test))
    if out:
        return out
    return _halves(ordered)


def _halves(experiments: Sequence[Experiment]) -> list[tuple[list[Experiment], list[Experiment]]]:
    # Too few experiments to deal out: split each in two halves in time.
    first, second = [], []
    for experiment in experiments:
        middle = experiment.start + experiment.samples // 2
        first.append(Experiment(experiment.v[:middle + 1], experiment.y[:middle + 1],
                                experiment.start, experiment.kind, experiment.level,
                                experiment.t0, experiment.source))
        second.append(Experiment(experiment.v, experiment.y, middle, experiment.kind,
                                 experiment.level, experiment.t0, experiment.source))
    return [(first, second), (second, first)]
