"""The parameters of ``identifier_node`` (node ``sdp_identifier``)."""

from hydro_sdp.core.control.idz_recalibration import RecalibrationPolicy
from hydro_sdp.ros.parameters.spec import ParameterSpec, ParameterTable

_POLICY = RecalibrationPolicy()

#: The parameters that are the recalibration thresholds (the fields of RecalibrationPolicy).
POLICY_PARAMETERS = ('significance', 'settle', 'confidence', 'min_change', 'cooldown')

IDENTIFIER_PARAMETERS = ParameterTable('identifier_node', 'sdp_identifier', (
    ParameterSpec('model_file', 'string', 'starting model (any map family)',
                  default_text='shipped J2 model', unit='path', read_only=True),
    ParameterSpec('joints', 'string_array',
                  'several joints, as named in JointState (overrides model_file and joint)',
                  read_only=True),
    ParameterSpec('model_files', 'string_array',
                  'one starting model per joint of joints, in the same order', unit='paths',
                  read_only=True),
    ParameterSpec('joint', 'string', 'joint name in JointState (one joint)',
                  default_text="the model's joint", read_only=True, on_demand=True),
    ParameterSpec('sample_period', 'double', 'period of joint_states', default=0.01, unit='s',
                  low=1e-4, high=1.0, read_only=True),
    ParameterSpec('noise_std', 'double', 'angle measurement noise (tunes the filter)',
                  default=0.03, unit='deg', low=1e-6, high=10.0, read_only=True),
    ParameterSpec('publish_period', 'double', 'time between published estimates (by stamps)',
                  default=0.1, unit='s', low=1e-3, high=60.0),
    ParameterSpec('auto_recalibrate', 'bool',
                  "set the controller's IDZ when the estimates call for it", default=False),
    ParameterSpec('controller_node', 'string', 'controller node whose IDZ is recalibrated',
                  default='pip_controller', read_only=True),
    ParameterSpec('control_period', 'double', 'control period of that controller (for the '
                  'IDZ slopes)', default=0.05, unit='s', low=1e-3, high=10.0, read_only=True),
    ParameterSpec('significance', 'double', 'edge change that counts as real',
                  default=_POLICY.significance, unit='standard deviations', low=1.0,
                  high=100.0),
    ParameterSpec('settle', 'double',
                  'time over which an edge estimate must have moved less than its standard '
                  'deviation', default=_POLICY.settle, unit='s', low=0.0, high=600.0),
    ParameterSpec('confidence', 'double', 'largest edge standard deviation to act on',
                  default=_POLICY.confidence, unit='fraction of the dead-zone width',
                  low=1e-4, high=1.0),
    ParameterSpec('min_change', 'double', 'smallest edge change worth a recalibration',
                  default_text=f'{_POLICY.min_change:g} x scale', unit='input units', low=0.0,
                  high=1e6),
    ParameterSpec('cooldown', 'double', 'least time between recalibrations',
                  default=_POLICY.cooldown, unit='s', low=0.0, high=3600.0),
    ParameterSpec('diagnostic_period', 'double', 'time between /diagnostics reports',
                  default=1.0, unit='s', low=0.01, high=60.0, read_only=True),
))
