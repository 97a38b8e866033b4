"""Scene side of rtaccel: mesh loading, procedural scenes, default cameras."""
