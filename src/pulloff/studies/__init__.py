"""Studies built from many runs: parameter sweeps and the validation of the seed's closed form."""
