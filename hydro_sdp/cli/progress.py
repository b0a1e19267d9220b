"""A small progress bar for long commands, drawn on stderr."""

from __future__ import annotations

import os
import sys
import time
from typing import TextIO


class ProgressBar:
    """
    Text progress bar: ``label [#####.....]  52%  3.1 s``.

    ``total``: amount of work at 100 %.
    ``stream``: where to draw; default ``sys.stderr``.
    ``delay``: seconds before the bar first appears.
    """

    def __init__(self, label: str, total: float, *, stream: TextIO | None = None,
                 delay: float = 2.0) -> None:
        self.label = label
        self.total = max(float(total), 1e-12)
        self.stream = stream if stream is not None else sys.stderr
        forced = os.environ.get('HYDRO_SDP_PROGRESS') == '1'
        self.enabled = forced or bool(getattr(self.stream, 'isatty', lambda: False)())
        self.delay = 0.0 if forced else delay
        self._start = time.monotonic()
        self._drawn = False
        self._last = 0.0

    def update(self, done: float, *, force: bool = False) -> None:
        """Show that ``done`` of ``total`` is finished."""
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._start < self.delay:
            return
        if self._drawn and now - self._last < 0.1 and not force:
            return
        fraction = min(max(done / self.total, 0.0), 1.0)
        width = 30
        filled = int(round(width * fraction))
        self.stream.write(f'\r{self.label} [{"#" * filled}{"." * (width - filled)}] '
                          f'{100 * fraction:3.0f}%  {now - self._start:5.1f} s')
        self.stream.flush()
        self._drawn = True
        self._last = now

    def close(self) -> None:
        """Finish the bar's line, if it was drawn."""
        if self._drawn:
            self.update(self.total, force=True)
            self.stream.write('\n')
            self.stream.flush()
            self._drawn = False

    def __enter__(self) -> ProgressBar:
        """Return the bar itself."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Close the bar."""
        self.close()
