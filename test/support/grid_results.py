"""
What the diagnosis grid named: one result per case, and the confusion table.

See :mod:`support.diagnosis_grid`.

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence


@dataclass(frozen=True)
class GridResult:
    """
    What the workflow named for one case.

    Parameters
    ----------
    word, program, units : str
        The case.
    named : str
        The first word named.
    mae_before, mae_after : float
        Validation MAE of the nominal and of the final model, degrees.
    shrink : float
        Largest share of the gap left for the case to count as right (0.5: halved).
    floor : float
        Validation MAE of a model that has the hidden word, degrees: the gap is the
        MAE above it (0: the gap is the whole MAE, as where the true joint is the
        generator's own).

    """

    word: str
    program: str
    units: str
    named: str
    mae_before: float
    mae_after: float
    shrink: float = 0.5
    floor: float = 0.0

    @property
    def right(self) -> bool:
        """Whether the right word came first and (when one is missing) the gap shrank enough."""
        if self.word == 'none':
            return self.named == 'none'
        return self.named == self.word and \
            self.mae_after - self.floor <= self.shrink * (self.mae_before - self.floor)

    @property
    def right_whole(self) -> bool:
        """Whether :attr:`right` holds with the gap taken as the whole MAE (floor 0)."""
        return self.word == 'none' and self.named == 'none' or self.named == self.word and \
            self.word != 'none' and self.mae_after <= self.shrink * self.mae_before


def confusion_table(results: Sequence[GridResult],
                    order: Sequence[str] = ()) -> list[str]:
    """
    Return the confusion table as Markdown rows: hidden word against first word named.

    Parameters
    ----------
    results : sequence of GridResult
        Grid results.
    order : sequence of str
        Order of the hidden words (others after, as they first appear).

    Returns
    -------
    list[str]
        Header, one row per hidden word (with the share right, gap halved), a total.

    """
    seen = list(dict.fromkeys([*order, *(r.word for r in results)]))
    hidden = [w for w in seen if any(r.word == w for r in results)]
    named = list(dict.fromkeys([*hidden, *sorted({r.named for r in results} - set(hidden))]))
    short = {w: w.replace('direction_dependent_delay', 'dir_delay')
             .replace('angle_dependent_velocity', 'angle_vel')
             .replace('velocity_saturation', 'saturation') for w in named}
    rows = ['| hidden \\ named | ' + ' | '.join(short[w] for w in named) + ' | right |',
            '|---' * (len(named) + 2) + '|']
    for word in hidden:
        mine = [r for r in results if r.word == word]
        counts = [sum(r.named == w for r in mine) for w in named]
        right = sum(r.right for r in mine)
        rows.append(f'| {short.get(word, word)} | ' + ' | '.join(str(c) for c in counts)
                    + f' | {right}/{len(mine)} |')
    right = sum(r.right for r in results)
    rows.append(f'| all | {" | ".join("" for _ in named)} | {right}/{len(results)} |')
    return rows


def shares(results: Sequence[GridResult], rule: str = 'gap halved') -> list[str]:
    """
    Return the two shares a grid is judged by, as lines to print.

    Parameters
    ----------
    results : sequence of GridResult
        Grid results.
    rule : str
        How "right" is judged for a hidden word, as the line says it.

    Returns
    -------
    list[str]
        The share of hidden words named right, and of correct models named none.

    """
    hidden = [r for r in results if r.word != 'none']
    correct = [r for r in results if r.word == 'none']
    right = sum(r.right for r in hidden)
    return [f'right word first and {rule}: {right}/{len(hidden)} '
            f'({100 * right / max(len(hidden), 1):.1f} %, target >= 95 %)',
            f'correct model named none: {sum(r.right for r in correct)}/{len(correct)} '
            '(target: all)']
