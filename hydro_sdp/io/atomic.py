"""Files written whole or not at all."""

from __future__ import annotations

from contextlib import contextmanager
import os
from pathlib import Path
import shutil
import signal
import tempfile
import threading
from typing import Iterator


def _read_umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


# Read once, at import, while nothing else runs: os.umask can only be read by setting it.
_UMASK = _read_umask()


@contextmanager
def interrupts_deferred() -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) back while the block creates or removes a temporary."""
    # None: a handler installed outside Python, which could not be put back.
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is None:
        yield
        return
    caught: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if caught:
            if callable(previous):
                previous(signal.SIGINT, None)      # the default handler: KeyboardInterrupt
            elif previous == signal.SIG_DFL:
                signal.raise_signal(signal.SIGINT)


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` so that the file appears whole or not at all."""
    target = Path(path)
    if target.is_dir():
        raise IsADirectoryError(f'{target} is a directory')
    target.parent.mkdir(parents=True, exist_ok=True)
    temporary: str | None = None
    try:
        with interrupts_deferred():
            handle, temporary = tempfile.mkstemp(prefix=f'.{target.name}.', suffix='.tmp',
                                                 dir=target.parent)
        with os.fdopen(handle, 'wb') as stream:
            # mkstemp makes the file private; give it the mode a plain open() would.
            os.fchmod(stream.fileno(), 0o666 & ~_UMASK)
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temporary, target)
    except BaseException:
        if temporary is not None:
            with interrupts_deferred():
                Path(temporary).unlink(missing_ok=True)
        raise
    return target


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write UTF-8 ``text`` to ``path`` whole or not at all (see :func:`atomic_write_bytes`)."""
    return atomic_write_bytes(path, text.encode('utf-8'))


@contextmanager
def atomic_directory(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Build a directory under a temporary name and move it to ``path`` when done."""
    target = Path(path)
    if target.exists() and not target.is_dir():
        raise FileExistsError(f'{target} exists and is not a directory')
    target.parent.mkdir(parents=True, exist_ok=True)
    work: Path | None = None
    try:
        with interrupts_deferred():
            work = Path(tempfile.mkdtemp(prefix=f'.{target.name}.', suffix='.tmp',
                                         dir=target.parent))
        building = work / target.name
        yield building
        if not building.exists():
            building.mkdir()
        # Both renames or neither: between them the old directory sits in ``work``.
        with interrupts_deferred():
            if target.exists():
                os.replace(target, work / 'replaced')
            os.replace(building, target)
    finally:
        if work is not None:
            with interrupts_deferred():
                shutil.rmtree(work, ignore_errors=True)
