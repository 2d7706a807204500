"""The run's crash-safe store of evaluated tests."""
from .store import Archive, TestRecord, read_records

__all__ = ["Archive", "TestRecord", "read_records"]
