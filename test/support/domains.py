"""
ROS domains for tests that start node processes.

The suite runs on a few workers (pytest-xdist, ``-n auto``); each draws its domains from its
own range, so that the nodes of two process tests running at once never find each other.
Within a worker the domains are drawn in turn from a random start, so that a test never
meets the leftovers of the test before it. Two suites on one host (two checkouts) keep apart
when one sets ``HYDRO_SDP_DOMAIN_SLOT`` to a slot past the other's workers.
"""

import itertools
import os
import random

#: Domains per slot, and slots; domain ids 1..232 are valid with the default port mapping.
SPAN = 29
SLOTS = 8


def _worker() -> int:
    name = os.environ.get('PYTEST_XDIST_WORKER', 'gw0')
    first = int(os.environ.get('HYDRO_SDP_DOMAIN_SLOT', '0'))
    return (first + int(name.removeprefix('gw') or 0)) % SLOTS


_NEXT = itertools.cycle(range(SPAN))
for _ in range(random.randrange(SPAN)):
    next(_NEXT)


def fresh_domain() -> int:
    """Return a ROS domain id that no other worker uses and this worker has not just used."""
    return 1 + _worker() * SPAN + next(_NEXT)
