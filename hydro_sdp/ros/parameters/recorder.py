"""The parameters of ``bag_recorder``, node ``bag_recorder``: :mod:`hydro_sdp.ros.bag_recorder`."""

from hydro_sdp.ros.parameters.spec import ParameterSpec, ParameterTable

RECORDER_PARAMETERS = ParameterTable('bag_recorder', 'bag_recorder', (
    ParameterSpec('output', 'string', 'bag folder to create; refused if it exists',
                  default='', default_text='required', unit='path', read_only=True,
                  required=True),
    ParameterSpec('topics', 'string_array', 'topics to record',
                  default_text='`joint_states`, and `<j>/valve_command` and `<j>/setpoint` of '
                  'each joint `j` of `joint_names`', read_only=True),
    ParameterSpec('joint_names', 'string_array',
                  'joints whose command and set-point topics are recorded by default',
                  default=('j2',), read_only=True),
    ParameterSpec('storage', 'string',
                  'storage plugin: sqlite3, the one committed while recording, so a crash '
                  'loses at most flush_period', default='sqlite3', read_only=True,
                  choices=('sqlite3',)),
    ParameterSpec('flush_period', 'double',
                  'longest time between commits to disk: what a crash can lose', default=1.0,
                  unit='s', low=0.01, high=60.0, read_only=True),
    ParameterSpec('discovery_period', 'double',
                  'how often topics not yet advertised are looked up in the graph',
                  default=0.2, unit='s', low=0.01, high=10.0, read_only=True),
))
