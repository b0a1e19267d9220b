"""
Figures written as a blank PNG, for tests of what a command computes rather than of what it draws.

Drawing is most of a report's time (layout, ticks, text: about 0.6 s of CPU a figure).
The figures are drawn where they are the subject: ``test/plots``, the report tests (every
diagnosis figure, opened whole), ``test_sdp_cli``, the demo's test and
``test_cli_says_what_it_wrote``.
"""

from __future__ import annotations

from contextlib import contextmanager
import struct
from typing import Any, Iterator
import zlib

from matplotlib.figure import Figure
import pytest


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (struct.pack('>I', len(data)) + kind + data
            + struct.pack('>I', zlib.crc32(kind + data) & 0xFFFFFFFF))


#: A valid 1 x 1 white PNG.
BLANK_PNG = (b'\x89PNG\r\n\x1a\n'
             + _chunk(b'IHDR', struct.pack('>IIBBBBB', 1, 1, 8, 2, 0, 0, 0))
             + _chunk(b'IDAT', zlib.compress(b'\x00\xff\xff\xff'))
             + _chunk(b'IEND', b''))


def _blank_savefig(self: Figure, target: Any, *args: Any, **kwargs: Any) -> None:
    if hasattr(target, 'write'):
        target.write(BLANK_PNG)
    else:
        with open(target, 'wb') as file:
            file.write(BLANK_PNG)


@contextmanager
def figures_not_drawn() -> Iterator[None]:
    """Within the block, every ``Figure.savefig`` writes :data:`BLANK_PNG` instead."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Figure, 'savefig', _blank_savefig)
        yield
