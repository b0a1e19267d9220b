"""
Files written whole or not at all, and the YAML model file.

Every file hydro_sdp writes goes through :func:`atomic_write_bytes` or
:func:`atomic_directory`: the content is produced beside the target under a
temporary name and renamed into place only when complete, so an interrupted
run never leaves a partial model, bag or figure behind.

"""

from __future__ import annotations

from contextlib import contextmanager
import os
from pathlib import Path
import shutil
import signal
import tempfile
import threading
from typing import Any, Callable, Iterator, Mapping

from hydro_sdp.core.controller_spec import ControllerSpec, design_from_model
from hydro_sdp.core.errors import HydroSdpError, ModelFileError
from hydro_sdp.core.model import JointModel
from hydro_sdp.core.safety import check_controller_fits
import yaml


def _read_umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


# Read once, at import, while nothing else runs: os.umask can only be read by setting it.
_UMASK = _read_umask()


@contextmanager
def interrupts_deferred() -> Iterator[None]:
    """
    Hold Ctrl-C (SIGINT) back for the duration of the block (creating or removing a temporary).

    A SIGINT that arrives meanwhile is acted on when the block ends, so a
    temporary file is never created without its cleanup being armed, nor left
    half-removed. Only the main thread can receive KeyboardInterrupt; elsewhere
    the block runs as is.
    """
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
    """
    Write ``data`` to ``path`` so that the file appears whole or not at all.

    Parameters
    ----------
    path : str or PathLike
        Target file; its folder is created if missing.
    data : bytes
        Content.

    Returns
    -------
    Path
        The target path.

    """
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
    """
    Build a directory under a temporary name and move it to ``path`` when done.

    The yielded path does not exist yet (rosbag2 writers create their folder).
    An existing ``path`` is replaced only after the new one is complete; if the
    block raises, nothing at ``path`` changes.

    Parameters
    ----------
    path : str or PathLike
        Final directory.

    Yields
    ------
    Path
        Where to build the directory.

    """
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


def read_text(path: str | os.PathLike[str], error: type[HydroSdpError] = ModelFileError, *,
              kind: str = 'a file', byte_order_mark: bool = False) -> str:
    """
    Read a whole UTF-8 text file; each failure is one line naming the file.

    Parameters
    ----------
    path : str or PathLike
        File to read.
    error : type of HydroSdpError
        The error raised.
    kind : str
        What the file should be, for the message on a directory.
    byte_order_mark : bool
        Whether a leading byte-order mark is dropped.

    Returns
    -------
    str
        The text.

    Raises
    ------
    HydroSdpError
        Of type ``error``, if the file is missing, a directory, unreadable or
        not UTF-8.

    """
    source = Path(path)
    if source.is_dir():
        raise error(f'{source} is a directory, not {kind}')
    try:
        return source.read_text(encoding='utf-8-sig' if byte_order_mark else 'utf-8')
    except FileNotFoundError:
        raise error(f'{source}: no such file') from None
    except UnicodeDecodeError as failure:
        raise error(f'{source}: not UTF-8 text (byte {failure.start})') from None
    except OSError as failure:
        raise error(f'{source}: cannot read: {failure}') from None


def load_yaml(path: str | os.PathLike[str]) -> Any:
    """
    Read a YAML document with safe loading.

    Parameters
    ----------
    path : str or PathLike
        File to read.

    Returns
    -------
    Any
        The parsed document.

    Raises
    ------
    ModelFileError
        If the file is missing, a directory, empty or not YAML.

    """
    source = Path(path)
    text = read_text(source)
    if not text.strip():
        raise ModelFileError(f'{source}: file is empty')
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, 'problem_mark', None)
        where = f' at line {mark.line + 1}' if mark is not None else ''
        raise ModelFileError(f'{source}: not valid YAML{where}') from None


def _load(path: str | os.PathLike[str], build: Callable[[Any], Any]) -> Any:
    """Read a YAML file and build an object from it; errors name the file."""
    data = load_yaml(path)
    try:
        return build(data)
    except ModelFileError as error:
        raise ModelFileError(f'{path}: {error}') from None


def load_model(path: str | os.PathLike[str]) -> JointModel:
    """
    Load and validate a model file (docs/interfaces.md section 1).

    Parameters
    ----------
    path : str or PathLike
        Model file.

    Returns
    -------
    JointModel
        The validated model.

    Raises
    ------
    ModelFileError
        With the file name, the key and the reason.

    """
    return _load(path, JointModel.from_mapping)


def dump_model(model: JointModel) -> str:
    """Return the YAML text of a model file."""
    return _yaml_text(model.to_mapping())


def _yaml_text(data: Mapping[str, Any]) -> str:
    """YAML text of a model or controller file: keys in their order, lists inline."""
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None)


def save_model(model: JointModel, path: str | os.PathLike[str]) -> Path:
    """
    Write a model file whole or not at all.

    Parameters
    ----------
    model : JointModel
        The model.
    path : str or PathLike
        Target file.

    Returns
    -------
    Path
        The target path.

    """
    return atomic_write_text(path, dump_model(model))


def shipped_config(name: str) -> Path:
    """
    Path of a file shipped in the package's ``config`` folder.

    Looks in the installed share folder (``ros2 run`` installs) first, then in
    the source tree (virtual environment installs).

    Parameters
    ----------
    name : str
        File name, e.g. ``brokk_j2.yaml``.

    Returns
    -------
    Path
        The file.

    """
    candidates = [Path(__file__).resolve().parent.parent / 'config' / name]
    try:
        from ament_index_python.packages import get_package_share_directory
        candidates.insert(0, Path(get_package_share_directory('hydro_sdp')) / 'config' / name)
    except Exception:  # noqa: B902 - no ament index (plain venv): use the source tree
        pass
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    raise FileNotFoundError(f'shipped file {name} not found (looked in '
                            f"{', '.join(str(c) for c in candidates)})")


def default_model_path() -> Path:
    """Path of the shipped BROKK J2 model file."""
    return shipped_config('brokk_j2.yaml')


def load_controller(path: str | os.PathLike[str]) -> ControllerSpec:
    """
    Load and validate a controller file written by ``hydro-sdp design``.

    Parameters
    ----------
    path : str or PathLike
        Controller file.

    Returns
    -------
    ControllerSpec
        The controller; its closed loop is checked to be stable.

    """
    return _load(path, ControllerSpec.from_mapping)


def controller_for(model: JointModel, path: str | os.PathLike[str] | None,
                   control_period: float) -> ControllerSpec:
    """
    Return the controller of ``path`` checked against ``model``, or one designed from it.

    Parameters
    ----------
    model : JointModel
        The joint's model.
    path : str, PathLike or None
        Controller file (checked to be for this joint and valve range), or None to
        design the PIP-IDZ controller from the model.
    control_period : float
        Control period of a designed controller, s.

    Returns
    -------
    ControllerSpec
        The controller.

    """
    if path:
        spec = load_controller(path)
        check_controller_fits(spec, model)
        return spec
    return design_from_model(model, control_period=control_period)


def save_controller(spec: ControllerSpec, path: str | os.PathLike[str]) -> Path:
    """
    Write the controller ``spec`` to a file whole or not at all.

    ``path`` and the returned target path as in :func:`save_model`.

    """
    return atomic_write_text(path, _yaml_text(spec.to_mapping()))
