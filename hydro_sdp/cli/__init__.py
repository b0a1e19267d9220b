"""The ``hydro-sdp`` command line."""

import os
import sys
import types


_PREVIOUS = sys.excepthook


def _interrupted_on_the_way_in(kind: type[BaseException], error: BaseException,
                               trace: types.TracebackType | None) -> None:
    """End a Ctrl-C that lands while the command is still being imported as main() would."""
    if issubclass(kind, KeyboardInterrupt):
        sys.stderr.write('error: interrupted\n')
        sys.stderr.flush()
        os._exit(130)
    _PREVIOUS(kind, error, trace)


# The command's own handler is set inside main(); until then Python raises
# KeyboardInterrupt wherever the import is, and would print its traceback.
sys.excepthook = _interrupted_on_the_way_in
