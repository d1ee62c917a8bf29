"""shipid.report."""
