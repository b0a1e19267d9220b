"""
The fenced blocks of the README and the user guide, with the note written before each.

A block is run as it is written unless an HTML comment right before it says
otherwise:

* ``<!-- not run: REASON -->``: the block cannot run here (a ROS 2 workspace, a
  ``git clone``, an output shown); the reason must be given.
* ``<!-- file: PATH -->``: the block is a file the next blocks use; it is written to
  ``PATH`` in the scratch folder.
* ``<!-- same as: PATH -->``: the block shows a file of the repository; its YAML must
  equal that file's.
* ``<!-- expect: REGEX | REGEX ... -->``: the block is run, and each regular
  expression (separated by `` | ``, a bar between spaces) must match a line of its
  output (the figures the text quotes).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
import re

#: Languages of the blocks that are run: shell commands and Python.
RUN = ('bash', 'python')
_FENCE = re.compile(r'^```(\S*)\s*$')
_NOTE = re.compile(r'^<!--\s*(not run|file|same as|expect):\s*(.*?)\s*-->$')


@dataclass(frozen=True)
class Block:
    """
    One fenced block.

    Parameters
    ----------
    path : Path
        Markdown file.
    line : int
        Line of its opening fence (1-based).
    language : str
        Its language tag ('' without one).
    text : str
        Its content.
    note : str
        The note before it: ``not run``, ``file``, ``same as``, ``expect`` or ''.
    argument : str
        What follows the note's colon.

    """

    path: Path
    line: int
    language: str
    text: str
    note: str = ''
    argument: str = ''

    @property
    def where(self) -> str:
        """Return ``file:line`` for messages."""
        return f'{self.path.name}:{self.line}'

    @property
    def runs(self) -> bool:
        """Whether the test runs the block."""
        return self.language in RUN and self.note in ('', 'expect')

    def expected(self) -> list[str]:
        """Return the regular expressions its output must match."""
        if self.note != 'expect':
            return []
        return [part.strip() for part in self.argument.split(' | ') if part.strip()]


def blocks(path: Path) -> list[Block]:
    """Return the fenced blocks of a Markdown file, each with the note written before it."""
    lines = path.read_text().splitlines()
    found = []
    index = 0
    while index < len(lines):
        fence = _FENCE.match(lines[index])
        if fence is None:
            index += 1
            continue
        end = index + 1
        while end < len(lines) and not lines[end].startswith('```'):
            end += 1
        previous = index - 1
        while previous >= 0 and not lines[previous].strip():
            previous -= 1
        note = _NOTE.match(lines[previous].strip()) if previous >= 0 else None
        found.append(Block(path, index + 1, fence.group(1), '\n'.join(lines[index + 1:end]),
                           note.group(1) if note else '', note.group(2) if note else ''))
        index = end + 1
    return found


def commands(text: str) -> list[list[str]]:
    """
    Split a shell block into scenes of commands.

    Lines ending in a backslash continue on the next; comments are dropped; a blank
    line ends a scene (the nodes started in it are stopped before the next).
    """
    scenes: list[list[str]] = [[]]
    pending = ''
    for raw in text.splitlines():
        line = raw.rstrip()
        if not line.strip():
            if scenes[-1]:
                scenes.append([])
            continue
        if line.lstrip().startswith('#') and not pending:
            continue
        if line.endswith('\\'):
            pending += line[:-1].strip() + ' '
            continue
        scenes[-1].append(_without_comment(pending + line.strip()).strip())
        pending = ''
    return [scene for scene in scenes if scene]


def _without_comment(line: str) -> str:
    """Drop a trailing ``# comment`` outside quotes."""
    quote = ''
    for position, character in enumerate(line):
        if quote:
            quote = '' if character == quote else quote
        elif character in '\'"':
            quote = character
        elif character == '#' and (position == 0 or line[position - 1].isspace()):
            return line[:position]
    return line
