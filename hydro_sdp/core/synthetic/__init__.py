"""
Synthetic data: input programs, simulated experiments and a physics plant to test against.

:mod:`.programs` makes open-loop command programs, :mod:`.joint_experiments`
records them on a joint model with noise, and :mod:`.physics` is a plant built
from hydraulics and geometry rather than from the SDP model.

"""
