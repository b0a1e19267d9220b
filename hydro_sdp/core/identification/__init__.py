"""
Identification: from records of a joint to its model (docs/methods.md sections 1, 2, 7, 13).

Records are cut into experiments (:mod:`.segmentation`, at the valve's
:mod:`.rest` command and where :mod:`.end_stops` hold the joint), the dead time
and the valve lag are estimated (:mod:`.delay`, fitted around command changes by
:mod:`.change_windows`), the static map is fitted (:mod:`.map_fit`), its family
chosen on held-out experiments (:mod:`.family_choice`) and the stroke factor
fitted (:mod:`.stroke_fit`); :mod:`.identify` runs the whole, or sends routine
operation (a closed loop, an operator: few held levels) to :mod:`.routine`, and returns
an :class:`.identified.Identification` with the model's limits from :mod:`.limits`.
Beside it: SRIV/RIV
transfer functions (:mod:`.riv`), the online estimator of the nodes
(:mod:`.online`), Table 2 of the first paper (:mod:`.evaluation`) and its method
as a baseline (:mod:`.paper_baseline`).

"""
