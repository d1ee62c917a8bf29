"""Helpers of the methods' report sections (:mod:`shipid.report.sections._util`).

Each method's ``shipid.methods.<m>.report`` module registers, for its method, a default section that
presents the entries the method is expected to carry under the report convention (see
:mod:`shipid.report`) with the caption of the paper figure or table they reproduce; they are loaded
through :mod:`shipid.registry` when a report of that method is built. They only draw what is present;
a method's own further sections (``register_section``) come after.
"""
