"""
Typed errors of hydro_sdp.

Every error names the problem in one line, so that the command line and the
ROS nodes can show ``str(error)`` to a user as it is.

"""


class HydroSdpError(Exception):
    """Base class for all hydro_sdp errors."""


class ModelFileError(HydroSdpError, ValueError):
    """A model file, or the mapping read from it, is invalid."""


class DataError(HydroSdpError, ValueError):
    """Measured data cannot be used as given (NaN, stamps going back, no excitation...)."""


class BagError(HydroSdpError):
    """A rosbag2 bag cannot be used."""


class BagNotFoundError(BagError, FileNotFoundError):
    """The bag path does not exist or holds no storage file."""


class BagFormatError(BagError, ValueError):
    """The bag is of a format or serialisation that cannot be read."""


class BagReadError(BagError, OSError):
    """The bag's storage could not be read (truncated or corrupt file)."""


class BagWriteError(BagError, OSError):
    """The bag's storage could not be written (a full disk): what was committed stays."""


class TopicNotFoundError(BagError, LookupError):
    """A topic needed for a record is not in the bag."""


class JointNotFoundError(BagError, LookupError):
    """The requested joint is not in the bag's JointState messages."""


class ConfigurationError(HydroSdpError, ValueError):
    """A parameter or option has an invalid value."""
