"""isu-validate: search-based testing of VLM in-car scene understanding, validated against the real world."""
__version__ = "0.1.0"
