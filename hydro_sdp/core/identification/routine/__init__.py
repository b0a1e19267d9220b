"""Identification from routine operation (docs/methods.md section 15)."""
