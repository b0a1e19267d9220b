"""
Every real rosbag2 layout in ../shared/data/rosbag2_fixtures is read or refused clearly.

The fixtures are not part of the repository: without them (a plain clone, a colcon
workspace) this module is skipped with the path it looked in; HYDRO_SDP_FIXTURES
points it at another copy.
"""

from conftest import FIXTURES
from hydro_sdp.bags import EmptyBagError, inspect_bag, read_bag
from hydro_sdp.core.errors import BagFormatError, TopicNotFoundError
import pytest

if not FIXTURES.is_dir():  # pragma: no cover - the fixtures live beside the repository
    pytest.skip(f'no rosbag2 fixtures at {FIXTURES} (set HYDRO_SDP_FIXTURES to their folder)',
                allow_module_level=True)


def _bags():
    folders = {p.parent for p in FIXTURES.rglob('metadata.yaml')}
    split = {p.parent for p in FIXTURES.rglob('multiple_files_0.*')}
    files = set(FIXTURES.rglob('*.db3')) | set(FIXTURES.rglob('*.mcap'))
    return sorted(folders | split | files)


BAGS = _bags()
# Messages in each bag's storage (folder name, or storage file stem), as rosbag2 wrote them.
EXPECTED = {
    'empty_bag': 0, 'empty_bag_0': 0, 'only_services': 12, 'only_topics': 7,
    'topics_and_services': 13, 'convert_a': 150, 'rewriter_a': 150, 'rewriter_a_0': 150,
    'convert_b': 75, 'rewriter_b': 75, 'rewriter_b_0': 75, 'talker': 20, 'wbag': 6074,
    'wbag_0': 1246, 'wbag_1': 1240, 'wbag_2': 1240, 'wbag_3': 1240, 'wbag_4': 1108,
    'multiple_files': 3177, 'multiple_files_0': 1324, 'multiple_files_1': 1324,
    'multiple_files_2': 529, 'bag_with_topics_and_service_events': 10, 'cdr_test': 7,
    'cdr_test_0': 7, 'wrong_rmw_test': 7, 'wrong_rmw_test_0': 7, 'test_bag_for_seek': 5,
    'test_bag_for_seek_0': 5,
}


def _key(path):
    return path.stem if path.is_file() else path.name


def test_the_fixture_set_is_complete():
    assert len(BAGS) >= 50
    assert all(_key(bag) in EXPECTED for bag in BAGS)


@pytest.mark.parametrize('bag', BAGS, ids=lambda p: str(p.relative_to(FIXTURES)))
def test_fixture_is_read_or_refused_with_a_reason(bag):
    if bag.is_dir() and bag.name == 'wrong_rmw_test':
        with pytest.raises(BagFormatError, match='Serialization format .*wrong_format'):
            inspect_bag(bag)
        with pytest.raises(BagFormatError, match='wrong_format'):
            read_bag(bag)
        return
    info = inspect_bag(bag)
    # Folders whose metadata QoS text trips the reader are read from their storage files.
    assert info.message_count == EXPECTED[_key(bag)]
    if info.message_count == 0:
        with pytest.raises(EmptyBagError, match='holds no messages'):
            read_bag(bag)
    else:
        with pytest.raises(TopicNotFoundError, match=r'no sensor_msgs/msg/JointState topic '
                                                     r'\(topics: .+\]\)'):
            read_bag(bag)
