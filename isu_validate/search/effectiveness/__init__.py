"""How well a search finds failures: benchmark SUTs with planted blind spots, in-memory runs,
real-pipeline runs, and the RQ1/RQ2 summary that ``bench effectiveness`` prints."""
