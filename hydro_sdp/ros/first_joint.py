"""The one-joint names of the multi-joint nodes: attributes of their first joint."""

from operator import attrgetter


def first_joint(joints: str, path: str, doc: str, *, settable: bool = False) -> property:
    """
    Return a node property that reads ``path`` on the first of the node's per-joint objects.

    Parameters
    ----------
    joints : str
        Name of the node attribute holding the per-joint objects (``loops``, ``identified``).
    path : str
        Attribute of the first joint; dotted for a nested one (``gate.blind``).
    doc : str
        Docstring of the property.
    settable : bool
        Whether assigning the property assigns that attribute of the first joint (``path``
        must then be a plain name).

    Returns
    -------
    property
        Read-only unless ``settable``.

    """
    read = attrgetter(path)

    def get(node: object) -> object:
        return read(getattr(node, joints)[0])

    def put(node: object, value: object) -> None:
        setattr(getattr(node, joints)[0], path, value)

    return property(get, put if settable else None, doc=doc)
