"""Control: from a joint model to a controller that holds the joint (methods 4-6)."""
