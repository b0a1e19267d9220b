"""When a started Python process runs its program's own imports."""

from pathlib import Path
import time


def loading_extensions(pid, limit=30.0):
    """
    Wait until process ``pid`` maps a compiled module of site-packages (its imports run).

    Before that the interpreter itself may still be starting (its ``site`` module), where a
    Ctrl-C ends any program in CPython's own "Fatal Python error". Returns False if the
    process ended or ``limit`` s passed first.
    """
    end = time.monotonic() + limit
    while time.monotonic() < end:
        try:
            if '/site-packages/' in Path(f'/proc/{pid}/maps').read_text():
                return True
        except OSError:
            return False
        time.sleep(0.005)
    return False
