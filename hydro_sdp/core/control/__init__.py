"""
Control: from a joint model to a controller that holds the joint.

See methods 4-6.
"""
