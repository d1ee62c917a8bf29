"""Known answers: the true and published values the tests check against, one module per paper.

Each value carries its provenance (paper, table or equation, section) so that a reader can check it
against the source; the seed texts are in ``../shared/seeds`` and the readings we chose where the
print is garbled or wrong are in ``../shared/seeds/ERRATA.md``. The values are typed from the
papers, never computed by shipid: a test compares shipid's output with them.

Import them as ``from known.linder2015 import TABLE3_TRUE`` (``tests/conftest.py`` puts ``tests/``
on ``sys.path``, which works with ``--import-mode=importlib``).

* :mod:`known.linder2015` — Linder et al. (2015), seed 000: mass and centre of mass (mass-cm).
* :mod:`known.fossen1996` — Fossen, Sagatun & Sørensen (1996), seed 001: the DP supply vessel.
* :mod:`known.yoon_rhee2003` — Yoon & Rhee (2003), seed 002: EBM on ESSO OSAKA.
"""
