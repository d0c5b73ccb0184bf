"""tenscell: tensegrity models of the cytoskeleton and the rheology they predict."""
__version__ = "0.1.0"
