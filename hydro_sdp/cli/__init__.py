"""The ``hydro-sdp`` command line."""
