"""
The joint model: what a hydraulic joint is, and how it moves.

The model file as a frozen object (:mod:`.joint_model`), the static maps from
command to speed (:mod:`.static_maps`), the effects beyond them
(:mod:`.effects`), the records of measured joints (:mod:`.records`), the timing
rule that pairs commands with samples (:mod:`.timing`) and the simulation at any
sample period (:mod:`.simulation`, end stops by :mod:`.bounded_sum`; signals
beyond the joint's own by :mod:`.exogenous_signals`).

"""
