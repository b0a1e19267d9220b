"""
Control: from a joint model to a controller that holds the joint (docs/methods.md sections 4-6).

PIP design in non-minimal state space (:mod:`.pip_design`), the inverse
dead-zone (:mod:`.idz`), the controller file (:mod:`.controller_spec`) and the
runtime controller (:mod:`.pip_controller`) with its feedback schedule
(:mod:`.scheduling`), safety rules (:mod:`.safety`) and health
(:mod:`.health`); set-point trajectories (:mod:`.trajectory`) and two-link
kinematics (:mod:`.kinematics`); the loop simulated offline
(:mod:`.loop_simulation`) and checked (:mod:`.loop_check`); the online
recalibration of the IDZ (:mod:`.idz_recalibration`).

"""
