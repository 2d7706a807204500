"""The benchmark SUTs a user can name (``bench effectiveness --suts``), whose blind spots ``sut.planted``
plants. A leaf: the command line lists them in its options without loading numpy or the scene space."""

BENCHMARK_SUTS = ("blind-spots", "blind-spots-noisy", "random-spots")
