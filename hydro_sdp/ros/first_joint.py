"""The one-joint names of the multi-joint nodes: attributes of their first joint."""

from operator import attrgetter


def first_joint(joints: str, path: str, doc: str, *, settable: bool = False) -> property:
    """
    Return a node property that reads ``path`` on the first of the node's per-joint objects.

    ``joints``: name of the node attribute holding the per-joint objects (``loops``,
    ``identified``); ``path`` is dotted for a nested attribute (``gate.blind``).
    The property is read-only unless ``settable`` (``path`` must then be a plain name).
    ``path``: attribute of the first joint; dotted for a nested one (``gate.blind``).
    ``settable``: whether assigning the property assigns that attribute of the first joint
    (``path`` must then be a plain name).
    """
    read = attrgetter(path)

    def get(node: object) -> object:
        return read(getattr(node, joints)[0])

    def put(node: object, value: object) -> None:
        setattr(getattr(node, joints)[0], path, value)

    return property(get, put if settable else None, doc=doc)
