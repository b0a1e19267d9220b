"""The parameters of ``bag_player`` (node ``bag_player``): :mod:`hydro_sdp.ros.bag_player`."""

from hydro_sdp.ros.parameters.spec import ParameterSpec, ParameterTable

PLAYER_PARAMETERS = ParameterTable('bag_player', 'bag_player', (
    ParameterSpec('bag', 'string', 'bag to play', default='', default_text='required',
                  unit='path', read_only=True, required=True),
    ParameterSpec('rate', 'double', 'playback speed relative to the recording', default=1.0,
                  low=1e-3, high=1e3, read_only=True),
    ParameterSpec('publish_clock', 'bool', 'publish the bag time on /clock before each message',
                  default=False, read_only=True),
    ParameterSpec('loop', 'bool',
                  'play the bag again from its start when it ends, instead of exiting',
                  default=False, read_only=True),
    ParameterSpec('autostart', 'bool',
                  'start playing on a wall-clock timer at once (tests drive play_until)',
                  default=True, read_only=True),
))
