# noqa: A005 - the files of the project; the standard io is always imported absolutely.
"""
Files: written whole or not at all (:mod:`.atomic`), read with one-line errors (:mod:`.documents`).

The model (:mod:`.model_files`), controller (:mod:`.controller_files`), physics
plant (:mod:`.plant_files`) and trajectory and kinematics files
(:mod:`.trajectory_files`), and machines' logs: CSV, MDF4 and MATLAB files (:mod:`.logs`).

"""
