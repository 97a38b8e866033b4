"""The plots: analysis (Figs 4-6), cache figures (Figs 8, 9, 11), TUs sweeps (Figs 12-13), roofline; shared axes."""
