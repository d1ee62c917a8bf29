"""Identified models in the forms other tools take.

* :func:`state_space`: DP's low-frequency model (Fossen, Sagatun & Sørensen 1996, eqs. 50–52) and any
  MMG or Abkowitz model linearised about a straight run, as ``A, B, C, D`` with named states and inputs
  (:class:`StateSpace`; ``to_control()`` for python-control);
* :func:`nomoto`: first- and second-order Nomoto K, T, T1, T2, T3 of a manoeuvring model with standard
  errors (delta method or seeded Monte Carlo);
* :func:`write_params` / :func:`read_params`: the model as a plain TOML or YAML file with units and
  sources that ``shipid simulate`` reads back;
* :func:`to_shipmmg`: an MMG model in the parameter objects of shipmmg, with the terms it lacks named.

Each takes what :func:`load` takes: a Result or MODEL.json of ``shipid identify dp | ebm | mmg``,
``published:NAME``, a parameter file, or a packaged vessel name (``supply``, ``esso-osaka``).
"""

from shipid.export.nomoto import Nomoto, nomoto
from shipid.export.params import load, read_params, simulate_params, write_params
from shipid.export.shipmmg import ShipmmgExport, to_shipmmg
from shipid.export.source import Source, load_source
from shipid.export.statespace import StateSpace, state_space

__all__ = ["load", "load_source", "Source", "StateSpace", "state_space", "Nomoto", "nomoto", "write_params",
           "read_params", "simulate_params", "ShipmmgExport", "to_shipmmg"]
