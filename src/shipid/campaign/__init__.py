"""shipid.campaign."""
