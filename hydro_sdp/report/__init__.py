"""Report folders: figures and a ``summary.md`` that a person reads."""
