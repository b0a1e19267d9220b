"""
The nodes' parameters: one declarative table per node, and what is made from it.

* :mod:`~hydro_sdp.ros.parameters.spec`: :class:`ParameterSpec` and :class:`ParameterTable`;
* :mod:`~hydro_sdp.ros.parameters.node_parameters`: :class:`NodeParameters`, which
  declares a node's parameters from its table and checks and applies set requests whole
  (with :mod:`~hydro_sdp.ros.parameters.descriptors` and the
  :class:`~hydro_sdp.ros.parameters.request.ParameterRequest` its checks read);
* one table per node: :mod:`~hydro_sdp.ros.parameters.plant`,
  :mod:`~hydro_sdp.ros.parameters.controller`, :mod:`~hydro_sdp.ros.parameters.identifier`,
  :mod:`~hydro_sdp.ros.parameters.recorder`, :mod:`~hydro_sdp.ros.parameters.player`;
* :mod:`~hydro_sdp.ros.parameters.documents`: the parameter tables of the documentation
  and the shipped parameter file, written from the tables (and checked against them).

"""
