"""The package version, in one place: ``pyproject.toml`` reads it (``[tool.setuptools.dynamic]``), so do
``tenscell.__version__``, output manifests and the documentation."""

__version__ = "0.3.0"
