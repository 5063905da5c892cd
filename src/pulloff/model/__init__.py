"""The model as data: geometry, rheology, adhesion and loading (MODEL.md), no numerics."""
