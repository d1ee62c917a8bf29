"""shipid.models."""
