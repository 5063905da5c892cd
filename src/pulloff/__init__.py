"""pulloff: adhesive pull-off of a rigid flat punch from a visco-elastic half-space (MDR + Dugdale)."""

__version__ = "0.1.0"
