"""The package version, in one place (read by the build, the CLI and the batch records)."""

__version__ = "0.1.0"
