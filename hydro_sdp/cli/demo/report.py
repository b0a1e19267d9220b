"""What the ``hydro-sdp demo`` stages share: the report folder, its summary and JSON."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.plots import save_figure
from matplotlib.figure import Figure


@dataclass
class Report:
    """What the demo's stages leave for the summary."""

    out: Path
    short: bool
    seed: int
    sections: list[str] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    payload: dict = field(default_factory=dict)
    identified: JointModel | None = None

    def figure(self, figure: Figure, name: str) -> str:
        """Save a figure into ``figures/`` and return its path relative to the report."""
        save_figure(figure, self.out / 'figures' / name)
        return f'figures/{name}'

    def model(self) -> JointModel:
        """Return the model the identification stage left."""
        if self.identified is None:
            raise DataError('the demo stages run in order: identification comes first')
        return self.identified
