"""nn: surrogate networks (MLP per bulk property with SCG, export to C)."""
