"""``hydro-sdp reindex``: rebuild metadata.yaml of a bag whose recorder died."""

from __future__ import annotations

import argparse

from hydro_sdp.bags.reindex import METADATA_VERSION, reindex
from hydro_sdp.cli.common import Outcome, table

HELP = 'rebuild metadata.yaml of a bag from its sqlite3 storage files (a crashed recording)'
DESCRIPTION = f"""\
Rebuild a bag's metadata.yaml from its .db3 storage files, as `ros2 bag reindex`
does: every storage file is read, the messages of each topic are counted, and
the start time and duration are taken from the first and last message. The file
is written as metadata version {METADATA_VERSION} (rosbag2 on Jazzy); an existing one is
replaced, the storage files are not changed.

Use it on a bag whose recorder was killed before it could write metadata.yaml:
bag_recorder commits every flush_period (1 s by default), so the bag holds all
but the last second. A transaction cut short by the crash is rolled back by
sqlite when the file is opened.

example:
  hydro-sdp reindex run1
  hydro-sdp identify run1 --out j2_model.yaml
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``reindex`` command to the command line."""
    parser = subparsers.add_parser('reindex', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bag', metavar='BAG', help='bag folder holding .db3 storage files')
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> Outcome:
    """Run ``reindex``."""
    summary = reindex(args.bag)
    seconds = summary.duration_ns * 1e-9
    payload = {
        'bag': str(summary.folder), 'metadata': str(summary.folder / 'metadata.yaml'),
        'metadata_version': METADATA_VERSION, 'message_count': summary.count,
        'starting_time_ns': summary.start_ns, 'duration': seconds,
        'files': [{'path': f.path.name, 'message_count': f.count} for f in summary.files],
        'topics': [{'name': t.name, 'type': t.msgtype, 'message_count': t.count}
                   for t in summary.topics],
    }
    lines = [f'wrote {summary.folder / "metadata.yaml"}: {summary.count} messages in '
             f'{len(summary.files)} storage file(s), {seconds:.3f} s']
    lines += table([[t.name, t.msgtype, str(t.count)] for t in summary.topics],
                   ['topic', 'type', 'messages'])
    return Outcome(payload, lines)
