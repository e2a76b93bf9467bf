"""Dense, slow reference implementations used only by the tests and the benchmarks."""
