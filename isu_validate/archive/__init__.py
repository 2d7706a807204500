"""The run's crash-safe store of evaluated tests, and the one reader of a run directory."""
from .run_dir import RunDir, RunDirError, find_runs, open_run
from .store import Archive, TestRecord, read_records

__all__ = ["Archive", "RunDir", "RunDirError", "TestRecord", "find_runs", "open_run", "read_records"]
