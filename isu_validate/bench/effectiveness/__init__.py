"""``bench effectiveness``: how well a search finds failures. In-memory runs against the planted
benchmark SUTs (``isu_validate.sut.planted``) or SUTs emulated from stored runs, real-pipeline runs,
the known-risk bound, and the RQ1/RQ2 summary it prints (``command.py`` holds the options)."""


def register_bench(sub) -> None:
    from .command import register_bench as register   # the harness's modules stay importable on their own
    register(sub)
