"""``hydro-sdp demo``: the command (:mod:`.command`), its stages and its report folder."""
