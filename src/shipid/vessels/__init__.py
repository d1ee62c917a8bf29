"""shipid.vessels."""
