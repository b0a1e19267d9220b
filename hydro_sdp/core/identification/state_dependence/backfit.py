"""
Back-fitting several state-dependent parameters, ``z_k = sum_i x_ik p_i(chi_ik) + e_k``.

The reasoning is in docs/methods.md section 14.4.

"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.state_dependence.nvr import NvrEstimate
from hydro_sdp.core.identification.state_dependence.ordering import (
    MAX_GROUPS, order_by_state, Ordering)
from hydro_sdp.core.identification.state_dependence.random_walk import (
    group_stats, inner, order_of, TvpKind)
from hydro_sdp.core.identification.state_dependence.shares import held_out_reduction
from hydro_sdp.core.identification.state_dependence.significance import dependence_test
from hydro_sdp.core.identification.state_dependence.smoothing import (
    smooth_parameter, SmoothedParameter)
import numpy as np

#: Passes in which the NVRs are re-estimated (CAPTAIN's ``nvr = -2``).
OPTIMISE_PASSES = 2
#: Back-fitting stops when the squared residual changes by less than this share of the base's.
TOLERANCE = 1e-5
#: Most passes.
MAX_PASSES = 30
#: Significance level of the dependence test.
ALPHA = 0.01


@dataclass(frozen=True, eq=False)
class Term:
    """
    One term ``x p(chi)`` of a back-fitted model.

    Parameters
    ----------
    name : str
        What the parameter is (``a1``, ``b+``...).
    regressor : FloatArray
        ``x`` at every sample (zero: the sample says nothing about ``p``).
    state : FloatArray
        ``chi`` at every sample.
    kind : str
        ``rw`` or ``irw``.
    nvr : float or None
        Fixed NVR (0: constant); None: estimated by maximum likelihood.
    additive : bool
        The term adds a second dependence to another term with the same regressor
        (``x (p1(chi1) + p2(chi2))``): it has no constant of its own in the base fit,
        and starts from zero.
    test : bool
        Whether its dependence is tested (bootstrap p-value; NaN when not).

    """

    name: str
    regressor: FloatArray
    state: FloatArray
    kind: TvpKind = 'rw'
    nvr: float | None = None
    additive: bool = False
    test: bool = True


@dataclass(frozen=True, eq=False)
class TermEstimate:
    """
    A back-fitted term with its weight of evidence.

    Attributes
    ----------
    standard_error : FloatArray
        Standard error per group.
    parameter : FloatArray
        The parameter at every sample.
    constant : float
        The parameter held constant (least squares on the partial residual).
    constant_se : float
        Its standard error.
    reduction : float
        Squared residual removed by letting the parameter follow the state (in-sample).
    share : float
        Held-out reduction (:mod:`hydro_sdp.core.identification.state_dependence.shares`, 0 when
        negative) over the base model's squared residual.
    p_value : float
        Bootstrap p-value of ``reduction`` (1 when the parameter came out constant).
    block : int
        Block length of the bootstrap, samples.
    fit_share : float
        In-sample ``reduction`` over the base model's squared residual.

    """

    term: Term
    ordering: Ordering
    smoothed: SmoothedParameter
    standard_error: FloatArray
    parameter: FloatArray
    constant: float
    constant_se: float
    reduction: float
    share: float
    p_value: float
    block: int = 0
    fit_share: float = 0.0

    @property
    def nvr(self) -> float:
        """Return the NVR of the parameter's walk (0: no dependence)."""
        return self.smoothed.nvr.nvr

    @property
    def values(self) -> FloatArray:
        """Return the state value of each group."""
        return self.ordering.values

    @property
    def estimate(self) -> FloatArray:
        """Return the parameter per group."""
        return self.smoothed.estimate

    @property
    def significant(self) -> bool:
        """Whether the dependence is significant: ``p_value <= ALPHA``."""
        return self.p_value <= ALPHA


@dataclass(frozen=True, eq=False)
class Backfit:
    """
    A back-fitted model and its base.

    Attributes
    ----------
    terms : tuple[TermEstimate, ...]
        The terms, in the order given.
    fitted : FloatArray
        ``sum_i x_i p_i`` at every sample.
    base : FloatArray
        The constant parameters of the terms that are not additive (least squares over them at
        once).
    base_se : FloatArray
        Their standard errors.

    """

    terms: tuple[TermEstimate, ...]
    fitted: FloatArray
    residual_sum: float
    base_residual_sum: float
    base: FloatArray
    base_se: FloatArray
    passes: int
    converged: bool

    @property
    def share(self) -> float:
        """Return the share of the base model's squared residual the dependences remove."""
        if not self.base_residual_sum > 0.0:
            return 0.0
        return max(0.0, 1.0 - self.residual_sum / self.base_residual_sum)

    def term(self, name: str) -> TermEstimate:
        """Return the term called ``name``."""
        for estimate in self.terms:
            if estimate.term.name == name:
                return estimate
        raise KeyError(name)


def base_fit(z: FloatArray, regressors: FloatArray) -> tuple[FloatArray, FloatArray, float]:
    """
    Least-squares constant parameters of ``z = X p + e``.

    Returns: parameters, their standard errors, squared residual.
    """
    X = np.asarray(regressors, dtype=np.float64)
    norms = np.sqrt(np.einsum('ij,ij->j', X, X))
    if np.any(norms == 0.0):
        raise DataError('a regressor is zero at every sample (a term never excited)')
    scaled = X / norms
    normal = np.einsum('ij,ik->jk', scaled, scaled)
    if np.linalg.cond(normal) > 1e12:
        raise DataError('the regressors are linearly dependent (a term never excited?)')
    inverse = np.linalg.inv(normal)
    coefficients = inverse @ np.einsum('ij,i->j', scaled, z) / norms
    residual = z - np.einsum('ij,j->i', X, coefficients)
    rss = inner(residual, residual)
    dof = max(z.size - X.shape[1], 1)
    return coefficients, np.sqrt(np.diag(inverse) * rss / dof) / norms, rss


def backfit(z: FloatArray, terms: Sequence[Term], *, max_groups: int | None = MAX_GROUPS,
            replicates: int = 199, seed: int = 0, segment: IntArray | None = None,
            max_passes: int = MAX_PASSES, tolerance: float = TOLERANCE,
            start: Sequence[FloatArray | None] | None = None,
            runs: IntArray | None = None) -> Backfit:
    """
    Back-fit the terms' state-dependent parameters to ``z``, and weigh each.

    ``max_groups``: most groups per state (:func:`.ordering.order_by_state`).
    ``replicates``: bootstrap replicates of each term's test (0: no test, p-values NaN).
    ``segment``: record of every sample, for the held-out shares (None: one record).
    ``tolerance``: convergence threshold on the squared residual, as a share of the base's.
    ``start``: per term, its parameter at every sample to start from (a fit of fewer terms); None:
    the base model's constant (zero for an additive term).
    ``runs``: run of every sample (a command held), where the tests' blocks may be cut
    (:func:`~hydro_sdp.core.identification.state_dependence.significance.dependence_test`).
    """
    z = np.asarray(z, dtype=np.float64)
    if not terms:
        raise DataError('no terms to fit')
    regressors = np.column_stack([np.asarray(t.regressor, dtype=np.float64) for t in terms])
    if regressors.shape[0] != z.size:
        raise DataError(f'{z.size} observations but {regressors.shape[0]} regressor rows')
    own = [i for i, t in enumerate(terms) if not t.additive]
    if not own:
        raise DataError('every term is additive: none carries the constant')
    base, base_se, rss_base = base_fit(z, regressors[:, own])
    orderings = [order_by_state(t.state, regressors[:, i], max_groups=max_groups)
                 for i, t in enumerate(terms)]
    constants = np.zeros(len(terms))
    constants[own] = base
    parameters = [np.full(z.size, float(value)) for value in constants]
    for i, given in enumerate(start or ()):
        if given is not None:
            parameters[i] = np.array(given, dtype=np.float64)
    nvrs: list[float | NvrEstimate | None] = [t.nvr for t in terms]
    smoothed: list[SmoothedParameter] = []
    fitted = np.einsum('ij,ij->i', regressors, np.column_stack(parameters))
    previous = rss_base
    passes, converged = 0, False
    while passes < max_passes and not converged:
        smoothed = []
        for i, term in enumerate(terms):
            samples = orderings[i].samples
            x = regressors[samples, i]
            partial = z[samples] - fitted[samples] + x * parameters[i][samples]
            optimise = term.nvr is None and passes < OPTIMISE_PASSES
            stats = group_stats(partial, x, orderings[i].group, orderings[i].groups)
            result = smooth_parameter(stats, term.kind, None if optimise else nvrs[i])
            nvrs[i] = result.nvr
            updated = result.estimate[orderings[i].group]
            # Only the samples in the ordering: elsewhere the regressor is zero.
            fitted[samples] += x * (updated - parameters[i][samples])
            parameters[i][samples] = updated
            smoothed.append(result)
        passes += 1
        rss = float(np.sum((z - fitted) ** 2))
        settled = abs(previous - rss) <= tolerance * max(rss_base, 1e-300)
        converged = len(terms) == 1 or (passes >= OPTIMISE_PASSES and settled)
        previous = rss
    parameters = [ordering.at_samples(result.estimate, term.state)
                  for ordering, result, term in zip(orderings, smoothed, terms)]
    residual = z - fitted
    estimates = tuple(_weigh(residual, regressors[:, i], terms[i], orderings[i], smoothed[i],
                             parameters[i], rss_base, replicates, seed + i, segment, runs)
                      for i in range(len(terms)))
    return Backfit(estimates, fitted, inner(residual, residual), rss_base, base,
                   base_se, passes, converged)


def with_tests(fit: Backfit, z: FloatArray, names: Sequence[str], *, replicates: int = 199,
               seed: int = 0, segment: IntArray | None = None,
               runs: IntArray | None = None) -> Backfit:
    """
    Return a back-fit with the terms ``names`` tested, as if fitted with ``test=True``.

    ``fit``: a back-fit of ``z`` made with ``replicates``, ``seed`` and ``segment``.
    """
    residual = np.asarray(z, dtype=np.float64) - fit.fitted
    terms = tuple(
        _weigh(residual, np.asarray(e.term.regressor, dtype=np.float64),
               replace(e.term, test=True), e.ordering, e.smoothed, e.parameter,
               fit.base_residual_sum, replicates, seed + i, segment, runs)
        if e.term.name in names else e for i, e in enumerate(fit.terms))
    return replace(fit, terms=terms)


def _weigh(residual: FloatArray, x: FloatArray, term: Term, ordering: Ordering,
           smoothed: SmoothedParameter, parameter: FloatArray, rss_base: float, replicates: int,
           seed: int, segment: IntArray | None, runs: IntArray | None) -> TermEstimate:
    """Return one converged term with its share, its constant and its p-value."""
    stats = smoothed.stats
    total_weight = float(np.sum(stats.weight))
    offset = float(np.sum(stats.moment)) / total_weight
    constant = stats.reference + offset
    # Squared residual with the parameter held constant, less that with it following the state.
    held = stats.total - offset * float(np.sum(stats.moment))
    observed = max(held - stats.residual_sum(smoothed.estimate), 0.0)
    n = stats.count
    sigma2 = inner(residual[ordering.samples], residual[ordering.samples]) / max(
        n - order_of(smoothed.kind), 1)
    constant_se = math.sqrt(sigma2 / total_weight)
    # The term's partial residual about its constant: the null's residual, and what the
    # test and the held-out share are formed on (sums of small numbers, 14.2).
    centred = residual + x * (parameter - constant)
    p_value, block = 1.0, 0
    if replicates <= 0 or not term.test:
        p_value = math.nan
    elif observed > 0.0 and ordering.groups > 1:
        # A random walk whatever draws the curve: its zero NVR is a constant, the null.
        test = dependence_test(centred, x, term.state, ordering, 'rw',
                               replicates=replicates, seed=seed, runs=runs, alpha=ALPHA)
        p_value, block = test.p_value, test.block
    held_out = held_out_reduction(centred, x, ordering, smoothed.kind, smoothed.nvr.nvr,
                                  segment)
    scale = rss_base if rss_base > 0.0 else np.inf
    return TermEstimate(term, ordering, smoothed, smoothed.standard_error(), parameter,
                        constant, constant_se, observed, max(held_out, 0.0) / scale,
                        p_value, block, observed / scale)
