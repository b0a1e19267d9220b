"""rosbag2 bags (sqlite3 and mcap) read and written with ``rosbags``, and what it cannot do."""

from hydro_sdp.bags.reading import BagData, read_bag, read_record, Series
from hydro_sdp.bags.storage import (
    BagInfo, EmptyBagError, FLOAT64, inspect_bag, JOINT_STATE, Progress, raw_messages,
    STORAGE_SUFFIXES, STORAGES, TopicInfo)
from hydro_sdp.bags.writing import Stamped, write_bag, write_topics

__all__ = [
    'BagData', 'BagInfo', 'EmptyBagError', 'FLOAT64', 'inspect_bag', 'JOINT_STATE', 'Progress',
    'raw_messages', 'read_bag', 'read_record', 'Series', 'Stamped', 'STORAGE_SUFFIXES', 'STORAGES',
    'TopicInfo', 'write_bag', 'write_topics',
]
