"""The nodes' parameters: one declarative table per node, and what is made from it."""
