"""The run's crash-safe store of evaluated tests."""
from .store import Archive, TestRecord

__all__ = ["Archive", "TestRecord"]
