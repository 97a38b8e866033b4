"""Design-space exploration and measurement: explore/ (the explorer), paper/, studies/, plots/; common.py is shared."""
