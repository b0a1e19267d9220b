"""The parameters of ``plant_node`` (node ``hydro_plant``): :mod:`hydro_sdp.ros.plant_node`."""

from hydro_sdp.ros.parameters.spec import ParameterSpec, ParameterTable

PLANT_PARAMETERS = ParameterTable('plant_node', 'hydro_plant', (
    ParameterSpec('sample_period', 'double', 'plant tick, the only timer of a simulated machine',
                  default=0.01, unit='s', low=1e-4, high=1.0, read_only=True),
    ParameterSpec('model_file', 'string', 'model of the simulated joint',
                  default_text='shipped J2 model', unit='path', read_only=True),
    ParameterSpec('model_files', 'string_array',
                  'models of several joints (overrides model_file; joint names must differ)',
                  unit='paths', read_only=True),
    ParameterSpec('noise_std', 'double',
                  'angle measurement noise (standard deviation); a new value applies from the '
                  'next tick', default=0.0, unit='deg', low=0.0, high=10.0),
    ParameterSpec('seed', 'int', 'noise seed; joint i draws from default_rng([seed, i])',
                  default=0, read_only=True),
    ParameterSpec('initial_angles', 'double_array',
                  'starting angle of each joint (default 0, or mid-travel when 0 is outside '
                  'the end stops)', unit='deg', read_only=True),
    ParameterSpec('dead_zone_shift', 'double_array',
                  'adds [lower, upper] to every dead-zone edge (wear, new parts; sdp and '
                  'sdp_dz maps); applies from the next tick once the whole request is accepted',
                  default=(0.0, 0.0), unit='input units', length=2),
    ParameterSpec('command_source', 'string',
                  'the only node whose valve commands are taken (fully qualified, '
                  "'/pip_controller'); '' takes any one node's: while a second node publishes "
                  'a valve_command topic, no command on it is taken and that valve is closed',
                  default='', read_only=True),
    ParameterSpec('command_rate_limit', 'double',
                  'most valve commands per second taken per joint (bursts of 10 allowed); '
                  'more are dropped, the command in force staying', default=1000.0,
                  unit='1/s', low=1.0, high=1e6, read_only=True),
    ParameterSpec('command_timeout', 'double',
                  'the valve closes when no command was taken for this long (0: never; set it '
                  "above the controller's control period)", default=0.0, unit='s', low=0.0,
                  high=60.0, read_only=True),
))
