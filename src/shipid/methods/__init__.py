"""shipid.methods."""
