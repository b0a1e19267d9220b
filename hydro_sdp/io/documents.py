"""Text and YAML documents: one reader for every file, each failure one line naming the file."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable, Mapping, TypeVar

from hydro_sdp.core.errors import HydroSdpError, ModelFileError
import yaml

#: Where the package's shipped files live in the source tree.
SOURCE_CONFIG = Path(__file__).resolve().parent.parent.parent / 'config'

#: What a document's builder makes (a model, a controller, a machine).
Built = TypeVar('Built')


def read_text(path: str | os.PathLike[str], error: type[HydroSdpError] = ModelFileError, *,
              kind: str = 'a file', byte_order_mark: bool = False) -> str:
    """
    Read a whole UTF-8 text file; each failure is one line naming the file.

    ``kind``: what the file should be, for the message on a directory.
    ``byte_order_mark``: whether a leading byte-order mark is dropped.
    Raises ``error`` (a HydroSdpError) if the file is missing, a directory, unreadable or not
    UTF-8.
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


def load_yaml(path: str | os.PathLike[str]) -> object:
    """
    Read a YAML document with safe loading.

    Returns: the parsed document, for a validator to check (mappings, lists, strings, numbers,
    booleans or None).
    Raises ModelFileError if the file is missing, a directory, empty or not YAML.
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


def load_document(path: str | os.PathLike[str], build: Callable[[object], Built]) -> Built:
    """Read a YAML file and build an object from it; the builder's errors name the file."""
    data = load_yaml(path)
    try:
        return build(data)
    except ModelFileError as error:
        raise ModelFileError(f'{path}: {error}') from None


def yaml_text(data: Mapping[str, object]) -> str:
    """YAML text of a model or controller file: keys in their order, lists inline."""
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None)


def shipped_config(name: str) -> Path:
    """Path of a file shipped in the package's ``config`` folder."""
    candidates = [SOURCE_CONFIG / name]
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
