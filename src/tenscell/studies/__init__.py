"""The paper's studies: claims, variants of the discussion, future work."""
