"""What every wing shares: xlsx names and error codes, the build record, safe files."""

__version__ = "0.1.0"   # the version every book records (pyproject.toml has the same)
