"""Golden reference traces (Embree via embreex), hit comparison and the Embree baseline benchmark."""
