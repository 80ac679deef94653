"""Study families: scene factories and the metrics of wedging, the Hertz benchmark, benchmarks."""
