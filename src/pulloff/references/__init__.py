"""Independent references: slow, accurate solvers of the same model by other methods."""
