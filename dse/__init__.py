"""Design-space exploration helpers (analysis plots)."""
