"""Identification: from records of a joint to its model (docs/methods.md sections 1, 2, 7, 13)."""
