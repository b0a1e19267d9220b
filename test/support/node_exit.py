"""How a node process may end after Ctrl-C or SIGTERM."""

import re
import warnings

from hydro_sdp.ros.runner import CLEANUP_LIMIT

#: faulthandler's first line when the bounded clean-up of ``hydro_sdp.ros.runner`` ran out.
TIMEOUT_LINE = re.compile(r'^Timeout \(\d+:\d\d:\d\d(\.\d+)?\)!$', re.MULTILINE)


def stuck_in_the_middleware(returncode, stderr):
    """
    Return whether the process ended because the middleware did not let go of its node.

    That is exit 1 with faulthandler's timeout report whose main thread is inside rclpy's
    own clean-up (``destroy_node``, ``try_shutdown``) called from the runner's: Fast DDS
    2.14 deadlocks now and then deleting a participant while a peer's endpoints vanish (3 in
    about 2,300 stops of nodes stopped together on a loaded host). The runner then ends the
    process after ``CLEANUP_LIMIT`` s, as documented; a test of the node's own exit accepts
    that one outcome and says so in a warning. A hang in a frame of ours is not excused.
    """
    timeout = TIMEOUT_LINE.search(stderr)
    if returncode != 1 or timeout is None:
        return False
    stack = stderr[timeout.end():]
    frames = re.findall(r'File "([^"]+)", line \d+ in (\w+)', stack)
    inside = bool(frames) and '/rclpy/' in frames[0][0] and \
        any(name == '_destroy' for _, name in frames)
    if inside:
        warnings.warn(f'the middleware held the node past {CLEANUP_LIMIT} s after the stop '
                      f'({frames[0][1]} in {frames[0][0]}); the process ended as bounded')
    return inside
