"""shipid.analysis."""
