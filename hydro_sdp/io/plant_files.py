"""The physics plant file (YAML, ``hydro_sdp/physics/v1``, docs/interfaces.md section 7)."""

from __future__ import annotations

import os

from hydro_sdp.core.synthetic.physics.plant import Machine
from hydro_sdp.io.documents import load_document


def load_machine(path: str | os.PathLike[str]) -> Machine:
    """Read a physics plant file (YAML, format ``hydro_sdp/physics/v1``) at ``path``."""
    return load_document(path, Machine.from_mapping)
