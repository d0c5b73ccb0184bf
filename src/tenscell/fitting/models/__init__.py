"""Every fittable model, one module per family, behind one registry."""
