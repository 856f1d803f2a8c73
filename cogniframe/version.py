"""cogniframe's version: a leaf module, so what records it (stack, the manifest) need not import
the package root, which reaches the API."""

__version__ = "0.1.0"  # pyproject.toml's [project] version
