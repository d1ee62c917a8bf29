"""shipid.studies."""
