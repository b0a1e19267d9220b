"""
State-dependent parameter identification and PIP-IDZ control of hydraulic joints.

The numerical core lives in :mod:`hydro_sdp.core` and never imports ROS; bag
files, the command line and plots are thin adapters around it.

"""

__version__ = '0.1.0'
