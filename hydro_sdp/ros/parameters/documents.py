"""The documentation's parameter tables and the shipped parameter file, from the nodes' tables."""

from __future__ import annotations

import argparse
from pathlib import Path
import re
import sys
import textwrap
from typing import Callable, Mapping

from hydro_sdp.ros.parameters.controller import CONTROLLER_PARAMETERS
from hydro_sdp.ros.parameters.identifier import IDENTIFIER_PARAMETERS
from hydro_sdp.ros.parameters.plant import PLANT_PARAMETERS
from hydro_sdp.ros.parameters.player import PLAYER_PARAMETERS
from hydro_sdp.ros.parameters.recorder import RECORDER_PARAMETERS
from hydro_sdp.ros.parameters.spec import ParameterSpec, ParameterTable, ParameterValue

#: Every node's table, in the order the documentation lists the nodes.
TABLES: tuple[ParameterTable, ...] = (PLANT_PARAMETERS, CONTROLLER_PARAMETERS,
                                      IDENTIFIER_PARAMETERS, RECORDER_PARAMETERS,
                                      PLAYER_PARAMETERS)

#: Where the shipped parameter file departs from the defaults, by node name: a simulated
#: J2 joint whose angle sensor has 0.02 deg of noise (seeded), and an identifier tuned to it.
SHIPPED: Mapping[str, Mapping[str, ParameterValue]] = {
    'hydro_plant': {'noise_std': 0.02, 'seed': 1},
    'sdp_identifier': {'noise_std': 0.02},
}

PARAMS_FILE = Path('config') / 'hydro_sdp.yaml'
MARKDOWN_FILES = (Path('docs') / 'interfaces.md', Path('docs') / 'guide' / 'nodes.md')

_BLOCK = re.compile(r'(<!-- parameters: (reference|guide) (\w+) -->\n)(.*?)'
                    r'(<!-- end parameters -->)', re.S)

PARAMS_HEADER = """\
# ROS 2 parameters of every hydro_sdp node, each with its value: the shipped setup of a
# simulated BROKK J2 joint whose angle sensor has 0.02 deg of noise. Load it with
#   ros2 run hydro_sdp <executable> --ros-args \\
#       --params-file <share>/hydro_sdp/config/hydro_sdp.yaml
# Keys are /**/<node name>, so the file applies in any namespace (-r __ns:=/arm2).
#
# Every parameter with a fixed default is listed with its value, defaults included: this file
# shows everything each node runs with, and a copy of it is the place to change any of it.
# The lines marked "shipped" are where this setup departs from the defaults. Parameters whose
# default a node computes (files, joint names, designed gains) are shown as comments.
# The file is written from the nodes' parameter tables (hydro_sdp/ros/parameters/, by
# `python -m hydro_sdp.ros.parameters.documents --write`) and a test fails when the two
# differ, so the defaults listed here cannot go stale.
#
# A -p given after --params-file wins over this file; one given before it is overridden for
# every parameter listed here. Relative paths are taken from the working directory.
"""


def type_text(spec: ParameterSpec) -> str:
    """Return the type as the documentation writes it (``double[2]``, ``string[]``)."""
    if spec.kind.endswith('_array'):
        return f"{spec.kind[:-len('_array')]}[{spec.length or ''}]"
    return spec.kind


def value_text(value: ParameterValue) -> str:
    """Return a value as YAML writes it: ``0.5``, ``true``, ``[0.0, 0.0]``, ``''``."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        plain = re.fullmatch(r'[A-Za-z_][\w./-]*', value) and value.lower() not in (
            'true', 'false', 'yes', 'no', 'on', 'off', 'null')
        return value if plain else "'" + value.replace("'", "''") + "'"
    return '[' + ', '.join(value_text(item) for item in value) + ']'


def default_text(spec: ParameterSpec) -> str:
    """Return the default as the documentation shows it."""
    if spec.default_text:
        return spec.default_text
    if spec.default is None:
        return 'unset'
    return f'`{value_text(spec.default)}`'


def number_text(value: float) -> str:
    """Return a number short: ``0.001``, ``1e-6``, ``1e6``, ``60``."""
    return re.sub(r'e([+-])0*(\d)', lambda m: 'e' + m.group(1).strip('+') + m.group(2),
                  f'{value:g}')


def range_text(spec: ParameterSpec) -> str:
    """Return the range or choices (``[0.001, 60]``, ```zero`, `smooth```), or ''."""
    if spec.low is not None and spec.high is not None:
        return f'[{number_text(spec.low)}, {number_text(spec.high)}]'
    if spec.choices:
        return ', '.join(f'`{choice}`' for choice in spec.choices)
    return ''


def _cell(text: str) -> str:
    # Angle brackets outside code spans would be read as HTML tags.
    parts = text.replace('|', '\\|').split('`')
    return '`'.join(part if index % 2 else part.replace('<', '&lt;').replace('>', '&gt;')
                    for index, part in enumerate(parts)) or '-'


def unit_range_text(spec: ParameterSpec) -> str:
    """Return the unit and the range or choices, comma-separated, or ''."""
    return ', '.join(part for part in (spec.unit, range_text(spec)) if part)


#: A column of a Markdown parameter table: its heading and its cell for a parameter.
Column = tuple[str, Callable[[ParameterSpec], str]]

#: The columns of docs/interfaces.md section 3.
REFERENCE_COLUMNS: tuple[Column, ...] = (
    ('parameter', lambda spec: f'`{spec.name}`'),
    ('type', type_text),
    ('default', lambda spec: _cell(default_text(spec))),
    ('unit / range', lambda spec: _cell(unit_range_text(spec))),
    ('run time', lambda spec: 'read-only' if spec.read_only else 'settable'),
    ('meaning', lambda spec: _cell(spec.description)))

#: The columns of the user guide.
GUIDE_COLUMNS: tuple[Column, ...] = (
    ('parameter', lambda spec: f'`{spec.name}`'),
    ('default', lambda spec: _cell(default_text(spec))),
    ('unit, range', lambda spec: _cell(unit_range_text(spec))),
    ('set at run time', lambda spec: 'no' if spec.read_only else 'yes'),
    ('what it sets', lambda spec: _cell(spec.description)))


def markdown_table(table: ParameterTable, columns: tuple[Column, ...]) -> str:
    """Return one node's parameters as a Markdown table, a row a parameter."""
    lines = ['| ' + ' | '.join(heading for heading, _ in columns) + ' |',
             '|' + '---|' * len(columns)]
    lines += ['| ' + ' | '.join(cell(spec) for _, cell in columns) + ' |'
              for spec in table.specs]
    return '\n'.join(lines) + '\n'


def reference_table(table: ParameterTable) -> str:
    """Return the Markdown table of docs/interfaces.md section 3 for one node."""
    return markdown_table(table, REFERENCE_COLUMNS)


def guide_table(table: ParameterTable) -> str:
    """Return the Markdown table of the user guide for one node."""
    return markdown_table(table, GUIDE_COLUMNS)


def params_file() -> str:
    """Return the shipped parameter file: every node, every parameter, the shipped values."""
    out = [PARAMS_HEADER]
    for table in TABLES:
        shipped = SHIPPED.get(table.node_name, {})
        out.append(f'/**/{table.node_name}:\n  ros__parameters:\n')
        for spec in table.specs:
            out.extend(_params_entry(spec, shipped))
    unknown = {node: sorted(set(values) - set(_listed(node))) for node, values in SHIPPED.items()}
    if any(unknown.values()):
        raise ValueError(f'shipped values of parameters the file does not list: {unknown}')
    return ''.join(out)


def _listed(node_name: str) -> list[str]:
    table = next(t for t in TABLES if t.node_name == node_name)
    return [spec.name for spec in table.specs if _is_listed(spec)]


def _is_listed(spec: ParameterSpec) -> bool:
    # A live key only for a fixed default: a computed one would be frozen here.
    return spec.default is not None and not spec.required and not spec.per_joint


def _params_entry(spec: ParameterSpec, shipped: Mapping[str, ParameterValue]) -> list[str]:
    listed = _is_listed(spec)
    about = spec.description
    if spec.required:
        about += ' (required)'
    elif not listed:
        about += f" (default: {default_text(spec).replace('`', '')})"
    lines = [f'    # {line}\n' for line in textwrap.wrap(about, 92, break_on_hyphens=False)]
    facts = [spec.unit] if spec.unit else []
    if spec.low is not None and spec.high is not None:
        facts.append(f'{number_text(spec.low)}..{number_text(spec.high)}')
    if spec.choices:
        facts.append(' or '.join(spec.choices))
    if spec.read_only:
        facts.append('read-only')
    if listed:
        assert spec.default is not None
        key = f'{spec.name}: {value_text(shipped.get(spec.name, spec.default))}'
        if spec.name in shipped:
            facts.append(f'shipped (default {value_text(spec.default)})')
    else:
        key = f"# {'<joint>.' if spec.per_joint else ''}{spec.name}: ..."
    comment = f"  # {', '.join(facts)}" if facts else ''
    return lines + [f'    {key:<28}{comment}'.rstrip() + '\n']


def render(text: str) -> str:
    """Return Markdown ``text`` with every parameter block written from the tables."""
    tables = {table.executable: table for table in TABLES}
    styles: dict[str, Callable[[ParameterTable], str]] = {'reference': reference_table,
                                                          'guide': guide_table}

    def block(match: re.Match[str]) -> str:
        style, executable = match.group(2), match.group(3)
        return match.group(1) + styles[style](tables[executable]) + match.group(5)
    return _BLOCK.sub(block, text)


def blocks(text: str) -> list[tuple[str, str]]:
    """Return the ``(style, executable)`` of every parameter block in Markdown ``text``."""
    return [(match.group(2), match.group(3)) for match in _BLOCK.finditer(text)]


def stale_files(root: Path, write: bool = False) -> list[Path]:
    """Return the files that differ from what the tables give; with ``write``, rewrite them."""
    wanted = {root / path: render((root / path).read_text()) for path in MARKDOWN_FILES}
    wanted[root / PARAMS_FILE] = params_file()
    stale = [path for path, text in wanted.items()
             if not path.exists() or path.read_text() != text]
    if write:
        for path in stale:
            path.write_text(wanted[path])
    return stale


def main(argv: list[str] | None = None) -> int:
    """Check (or with ``--write``, rewrite) the generated parameter documents; return 0 or 1."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--write', action='store_true', help='rewrite the files that differ')
    parser.add_argument('--root', type=Path, default=Path(__file__).resolve().parents[3],
                        help='repository to check (default: this checkout)')
    args = parser.parse_args(argv)
    stale = stale_files(args.root, write=args.write)
    for path in stale:
        print(f"{'rewrote' if args.write else 'differs from the tables'}: {path}")
    return 0 if args.write or not stale else 1


if __name__ == '__main__':
    sys.exit(main())
