"""Input and output: scene files, HDF5 results, the console and figures."""
