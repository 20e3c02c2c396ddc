"""Data layer: Algorithm 1's scripted policy, parallel collection and HDF5 data sets."""
