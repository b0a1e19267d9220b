# noqa: A005 - the files of the project; the standard io is always imported absolutely.
"""Files: written whole or not at all (:mod:`.atomic`), read with one-line errors."""
