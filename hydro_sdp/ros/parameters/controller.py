"""The parameters of ``controller_node`` (node ``pip_controller``)."""

from hydro_sdp.core.control.idz import IDZ_MODES
from hydro_sdp.core.control.plausibility import FEEDBACK_MARGIN
from hydro_sdp.core.control.safety import SETPOINT_MARGIN, STOP_BAND
from hydro_sdp.ros.parameters.spec import ParameterSpec, ParameterTable

CONTROLLER_PARAMETERS = ParameterTable('controller_node', 'pip_controller', (
    ParameterSpec('model_file', 'string', 'model of the joint (end stops, design)',
                  default_text='shipped J2 model', unit='path', read_only=True),
    ParameterSpec('controller_file', 'string',
                  "controller file from hydro-sdp design (interfaces.md section 6); '' designs "
                  'from the model at configuration', default='', unit='path', read_only=True),
    ParameterSpec('joints', 'string_array',
                  'several joints in one node, as named in JointState (overrides model_file, '
                  'controller_file and joint); names must differ', read_only=True),
    ParameterSpec('model_files', 'string_array',
                  'one model per joint of joints, in the same order', unit='paths',
                  read_only=True),
    ParameterSpec('controller_files', 'string_array',
                  "none, or one controller file per joint of joints ('' designs that joint "
                  'from its model)', unit='paths', read_only=True),
    ParameterSpec('control_period', 'double', 'control period when designing from a model',
                  default=0.05, unit='s', low=1e-3, high=10.0, read_only=True),
    ParameterSpec('joint', 'string',
                  'joint name in JointState and in the topic names (one joint; declared at '
                  'configuration)', default_text="the controller's joint", read_only=True,
                  on_demand=True),
    ParameterSpec('feedback_timeout', 'double',
                  'watchdog and stamp-freshness limit: the valve closes after this long '
                  'without valid feedback, on the node clock or a steady clock, whichever '
                  'passes first (a new value applies from the next sample and watchdog tick)',
                  default=0.5, unit='s', low=1e-3, high=60.0),
    ParameterSpec('setpoint_margin', 'double',
                  "set-points are kept this far inside the model's end stops (refused if no "
                  'set-point would be left between them)', default=SETPOINT_MARGIN, unit='deg',
                  low=0.0, high=90.0),
    ParameterSpec('stop_band', 'double',
                  'a set-point this close to the end of its range (setpoint_margin inside a '
                  'stop) is stop-side: once the joint is this close to it, or past it towards '
                  'the stop, the valve holds at rest (0: never)', default=STOP_BAND, unit='deg',
                  low=0.0, high=90.0),
    ParameterSpec('feedback_margin', 'double',
                  'feedback more than this beyond the end stops, or changing faster than twice '
                  "the joint's top speed plus this, is refused and the valve closed",
                  default=FEEDBACK_MARGIN, unit='deg', low=0.0, high=90.0),
    ParameterSpec('feedforward', 'bool',
                  'feed the set-point rate of trajectories forward through the IDZ (methods.md '
                  'section 4.9)', default=True),
    ParameterSpec('diagnostic_period', 'double', 'time between /diagnostics reports',
                  default=1.0, unit='s', low=0.01, high=60.0, read_only=True),
    ParameterSpec('autostart', 'bool',
                  'configure and activate at start (false: wait unconfigured for '
                  '~/change_state)', default=True, read_only=True),
    ParameterSpec('gains.f', 'double_array',
                  'PIP output feedback gains f0.., (deg per control sample) per deg',
                  default_text='designed', per_joint=True),
    ParameterSpec('gains.g', 'double_array', 'PIP input feedback gains g1.. (dimensionless)',
                  default_text='designed', per_joint=True),
    ParameterSpec('gains.k_i', 'double',
                  'PIP integral gain kI, (deg per control sample) per deg of error',
                  default_text='designed', low=0.0, high=10.0, per_joint=True),
    ParameterSpec('idz.dead_zone', 'double_array',
                  'IDZ edges, inside the valve range (only when the controller has an IDZ); '
                  'with a table, the commands where its increments leave 0: a new edge shifts '
                  'that branch by the change', default_text='designed', unit='input units',
                  length=2, per_joint=True),
    ParameterSpec('idz.slopes', 'double_array',
                  "IDZ slopes, within a factor 2 of the model's (its chord to the valve end to "
                  "its steepest); with a table, each branch's chord from its edge to two thirds "
                  "of its largest increment: a new slope scales that branch's increments by "
                  'new / old', default_text='designed',
                  unit='deg per control sample per input unit', length=2, per_joint=True),
    ParameterSpec('idz.beta', 'double', 'IDZ chatter band', default_text='designed (0.05)',
                  unit='deg per control sample', low=0.0, high=100.0, per_joint=True),
    ParameterSpec('idz.mode', 'string', 'IDZ mode', default_text='designed (zero)',
                  choices=IDZ_MODES, per_joint=True),
    ParameterSpec('idz.fade', 'double',
                  'IDZ fade-in band beyond the chatter band: the compensation leaves rest as '
                  'tanh((|u| - beta) / fade) instead of jumping to the edge (mode zero only; '
                  '0: none; methods.md section 5.2)', default_text='designed (0)',
                  unit='deg per control sample', low=0.0, high=100.0, per_joint=True),
))
